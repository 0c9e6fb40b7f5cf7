"""The case-file reference is the one the schema generates (one place), and the docs link
each other."""

from mpmflow.case import reference_page

from conftest import ROOT


def test_case_reference_page_is_generated_from_the_schema():
    text = (ROOT / "docs" / "reference.md").read_text()
    assert text == reference_page(), "run python scripts/update_readme_reference.py"


def test_readme_commands_are_the_ci_commands():
    readme = (ROOT / "README.md").read_text()
    ci = (ROOT / ".ci" / "run").read_text()
    assert "make test" in readme and "make dam-break" in readme
    assert "make test" in ci


def test_documentation_pages_are_linked_and_present():
    readme = (ROOT / "README.md").read_text()
    for page in ("docs/getting-started.md", "docs/theory.md", "docs/reference.md",
                 "docs/method.md", "benchmarks/README.md"):
        assert f"({page})" in readme, page
        assert (ROOT / page).is_file(), page
    assert "(docs/validation/README.md)" in readme  # written with the validation work


def test_every_example_says_what_it_shows_and_how_long_it_takes():
    for case in sorted((ROOT / "examples").glob("*.toml")):
        head = case.read_text().split("\n\n", 1)[0]
        assert head.startswith("#"), case.name
        assert "Shows:" in head and "Takes:" in head, case.name
