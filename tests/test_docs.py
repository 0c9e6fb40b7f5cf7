"""The case-file reference is the one the schema generates (one place), and the docs link
each other."""

import pytest
from conftest import ROOT

from mpmflow.case import reference_page


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
    for page in (
        "docs/getting-started.md",
        "docs/theory.md",
        "docs/reference.md",
        "docs/method.md",
        "benchmarks/README.md",
    ):
        assert f"({page})" in readme, page
        assert (ROOT / page).is_file(), page
    assert "(docs/validation/README.md)" in readme  # written with the validation work


def test_every_example_says_what_it_shows_and_how_long_it_takes():
    for case in sorted((ROOT / "examples").glob("*.toml")):
        head = case.read_text().split("\n\n", 1)[0]
        assert head.startswith("#"), case.name
        assert "Shows:" in head and "Takes:" in head, case.name


@pytest.mark.slow
def test_the_readme_python_example_runs_as_written(tmp_path, monkeypatch):
    """The Python API section's code, run as it stands (in a folder with the examples)."""
    import re
    import runpy

    readme = (ROOT / "README.md").read_text()
    section = readme.split("## Python API", 1)[1].split("\n## ", 1)[0]
    code = re.search(r"```python\n(.*?)```", section, re.S).group(1)
    (tmp_path / "examples").symlink_to(ROOT / "examples")
    (tmp_path / "example.py").write_text(code)
    monkeypatch.chdir(tmp_path)
    names = runpy.run_path(str(tmp_path / "example.py"))
    assert names["summary"]["status"] == "completed" and names["run"].status == "completed"
    assert len(names["t"]) == 31 and names["snap"].time == 0.3
    assert names["p"].shape == (31,) and names["data"]["x"].shape == (6498, 2)
