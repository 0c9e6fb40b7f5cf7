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
        "docs/notes/benchmarks-diary.md",
    ):
        assert f"({page})" in readme, page
        assert (ROOT / page).is_file(), page
    assert "(docs/validation/README.md)" in readme  # written with the validation work


BENCHMARKS = ROOT / "benchmarks"


def test_benchmarks_are_a_suite_that_keeps_its_history():
    """benchmarks/ (issue 40): each script of the suite is named in its README with a
    command and appends its figures to history.csv; each one-off study stands under
    investigations/ and is named there too; the README's links resolve."""
    import re

    readme = (BENCHMARKS / "README.md").read_text()
    suite = [
        p
        for p in [
            *BENCHMARKS.glob("*.py"),
            *BENCHMARKS.glob("mpi/*.py"),
            *BENCHMARKS.glob("peers/*.py"),
        ]
        if p.name != "history.py"
    ]
    assert len(suite) >= 7
    for p in suite:
        name = p.relative_to(ROOT).as_posix()
        assert name in readme, name
        assert "append(" in p.read_text(), f"{name} does not append to history.csv"
    studies = [
        p.relative_to(BENCHMARKS / "investigations")
        for p in BENCHMARKS.glob("investigations/**/*.py")
    ]
    assert studies
    for p in studies:
        assert f"`{p.as_posix()}`" in readme, p
    for link in re.findall(r"\]\(([^)#]+)\)", readme):
        assert (BENCHMARKS / link).exists(), link


def test_a_benchmark_appends_a_row_per_figure_to_the_history(tmp_path, monkeypatch):
    import csv

    monkeypatch.syspath_prepend(str(BENCHMARKS))
    import history

    with open(history.HISTORY, newline="") as f:
        assert tuple(next(csv.reader(f))) == history.COLUMNS  # the tracked file's header
    monkeypatch.setattr(history, "HISTORY", tmp_path / "history.csv")
    start = history.machine()
    history.append("dam_break", [("whole process (median)", 4.2612345, "s")], "a test", start)
    history.append("scaling 3D", [("time per step, 0.002 m", 0.4, "s")], start=start, threads=1)
    with open(tmp_path / "history.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert [r["benchmark"] for r in rows] == ["dam_break", "scaling 3D"]
    first = rows[0]
    assert first["value"] == "4.26123" and first["unit"] == "s" and first["note"] == "a test"
    assert first["commit"] == start["commit"] and first["machine"] == history.cpu_model()
    assert rows[1]["threads"] == "1" and rows[1]["cores"] == str(start["cores"])


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
