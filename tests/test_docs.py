"""The README's case-file reference is the one the schema generates (one place)."""

from mpmflow.case import reference_markdown

from conftest import ROOT


def test_readme_case_reference_is_generated_from_the_schema():
    text = (ROOT / "README.md").read_text()
    block = text.split("<!-- case-reference:start -->\n", 1)[1].split(
        "\n<!-- case-reference:end -->", 1)[0]
    assert block == reference_markdown(), "run python scripts/update_readme_reference.py"


def test_readme_commands_are_the_ci_commands():
    readme = (ROOT / "README.md").read_text()
    ci = (ROOT / ".ci" / "run").read_text()
    assert "make test" in readme and "make dam-break" in readme
    assert "make test" in ci
