"""The layout the architecture page promises (docs/architecture.md): one door to the
compiled core, boundaries decided in one package, no module too long to read."""

import re

from conftest import ROOT

SRC = ROOT / "src" / "mpmflow"
MODULES = sorted(p for p in SRC.rglob("*.py") if p.name != "_version.py")


def _code(path):
    """The module's text without comments and docstrings' mentions counting as calls: the
    lines that are not comments."""
    return "\n".join(
        line for line in path.read_text().splitlines() if not line.lstrip().startswith("#")
    )


def _rel(path):
    return path.relative_to(SRC).as_posix()


def test_only_the_state_package_imports_the_compiled_core():
    door = re.compile(
        r"^\s*(from \.+ import _core|from \.+_core|import mpmflow\._core"
        r"|from mpmflow import _core|from mpmflow\._core)",
        re.M,
    )
    importers = [_rel(p) for p in MODULES if door.search(_code(p))]
    assert importers and all(name.startswith("state/") for name in importers)


def test_boundaries_are_decided_in_one_package():
    """Which nodes are walls, which way they face and whether they hold the material: the
    wall tables (state.wall_pairs), the sides' conditions (no_slip_sides, uniform_walls)
    and the obstacles' node distances are asked for in boundaries/ only (case/ defines the
    conditions; state/ is the door to the core's kernels)."""
    calls = re.compile(
        r"\b(wall_pairs|apply_walls|no_slip_sides|uniform_walls|outlet_sides|"
        r"wall_conditions|node_distance|cut_cell_tensors)\("
    )
    allowed = ("boundaries/", "case/", "state/")
    outside = {
        _rel(p): sorted(set(calls.findall(_code(p))))
        for p in MODULES
        if not _rel(p).startswith(allowed) and calls.search(_code(p))
    }
    assert outside == {}


def test_no_module_is_over_500_lines():
    long = {_rel(p): n for p in MODULES if (n := len(p.read_text().splitlines())) > 500}
    assert long == {}


TESTS = ROOT / "tests"
# tests of the project as a whole (its layout, its documents, its examples, its command
# line) stand at the top; every other test lives in the folder of the package it tests
PROJECT_TESTS = {"test_architecture.py", "test_docs.py", "test_examples.py", "test_cli.py"}


def test_tests_mirror_the_packages():
    packages = {p.name for p in SRC.iterdir() if p.is_dir() and (p / "__init__.py").exists()}
    folders = {p.parent.relative_to(TESTS).as_posix() for p in TESTS.rglob("test_*.py")}
    top = {p.name for p in TESTS.glob("test_*.py")}
    assert top == PROJECT_TESTS
    assert folders - {"."} <= packages, sorted(folders - {"."} - packages)


def test_no_test_reaches_into_private_state():
    """Tests use what a user or a developer of another package may use: no attribute or
    function whose name starts with an underscore (dunders aside), of mpmflow or of a
    library."""
    private = re.compile(r"\.(_[a-z][A-Za-z0-9_]*)\b")
    found = {
        p.relative_to(TESTS).as_posix(): sorted(set(private.findall(_code(p))))
        for p in TESTS.rglob("test_*.py")
        if p.name != "test_architecture.py" and private.search(_code(p))
    }
    assert found == {}


def test_only_the_parallel_package_imports_mpi_and_petsc():
    """mpi4py and petsc4py come with the MPI environment only (make setup-mpi): imported
    in parallel/ alone, so that the one-process install runs without them."""
    door = re.compile(r"^\s*(from|import) (mpi4py|petsc4py)\b", re.M)
    importers = [_rel(p) for p in MODULES if door.search(_code(p))]
    assert importers and all(name.startswith("parallel/") for name in importers)
