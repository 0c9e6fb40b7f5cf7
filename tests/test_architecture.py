"""The layout the architecture page promises (docs/architecture.md): one door to the
compiled core, boundaries decided in one package, a case read without the engine, no import
cycles."""

import ast
import re
import subprocess
import sys

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


def _module(path):
    parts = list(path.relative_to(SRC.parent).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _type_checking(node):
    t = node.test
    return (isinstance(t, ast.Name) and t.id == "TYPE_CHECKING") or (
        isinstance(t, ast.Attribute) and t.attr == "TYPE_CHECKING"
    )


def _imports(path, names):
    """The mpmflow modules ``path`` imports at run time: at module level and inside its
    functions (a deferred import still ties the two), not under TYPE_CHECKING. Importing
    a.b.c imports the package a.b as well. The package face mpmflow/__init__.py is left out:
    its imports run on attribute access only (PEP 562), to start the command line quickly."""
    me = _module(path)
    if me == "mpmflow":
        return set()
    package = me if path.name == "__init__.py" else me.rpartition(".")[0]
    found = set()

    def walk(node):
        if isinstance(node, ast.If) and _type_checking(node):
            for n in node.orelse:
                yield from walk(n)
            return
        yield node
        for child in ast.iter_child_nodes(node):
            yield from walk(child)

    for node in walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            found.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                up = package.split(".")[: len(package.split(".")) - node.level + 1]
                base = ".".join(up + ([base] if base else []))
            for a in node.names:
                found.add(f"{base}.{a.name}" if f"{base}.{a.name}" in names else base)
    out = set()
    for name in found:
        if name not in names:
            continue
        out.add(name)
        parts = name.split(".")
        for k in range(2, len(parts)):  # the packages on the way, but not my own
            pkg = ".".join(parts[:k])
            if pkg in names and not me.startswith(pkg + "."):
                out.add(pkg)
    out.discard(me)
    return out


def _cycles(graph):
    """The strongly connected components of more than one module (Tarjan)."""
    index, low, stack, on, found = {}, {}, [], set(), []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in graph[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            part = set()
            while True:
                w = stack.pop()
                on.discard(w)
                part.add(w)
                if w == v:
                    break
            if len(part) > 1:
                found.append(sorted(part))

    for v in graph:
        if v not in index:
            visit(v)
    return found


def test_no_import_cycles():
    """No two modules of src/mpmflow import each other, directly or round a loop, at run
    time (imports inside functions count; TYPE_CHECKING's do not). Layers stand on one
    another: a module that needs a higher one's work takes it as an argument or moves."""
    paths = {_module(p): p for p in MODULES}
    graph = {name: _imports(path, paths) for name, path in paths.items()}
    assert _cycles(graph) == []


def test_the_cycle_finder_finds_a_cycle():
    """The check above can fail: a loop of three and a self-standing module."""
    graph = {"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}
    assert _cycles(graph) == [["a", "b", "c"]]


def test_reading_a_case_does_not_load_the_engine():
    """Loading and validating a case file, and `mpmflow keys`, import neither the compiled
    core nor the schemes nor the state package: what each scheme supports and each material's
    name and checks are data the case reads (case.capabilities, materials)."""
    script = (
        "import sys, io, contextlib\n"
        "from mpmflow.case import load_case\n"
        f"load_case({str(ROOT / 'examples' / 'dam_break.toml')!r})\n"
        f"load_case({str(ROOT / 'examples' / 'bingham_slump.toml')!r})\n"
        "from mpmflow.cli import main\n"
        "with contextlib.redirect_stdout(io.StringIO()):\n"
        "    main(['keys'])\n"
        "engine = ('mpmflow._core', 'mpmflow.state', 'mpmflow.schemes', 'mpmflow.simulation')\n"
        "print(sorted(m for m in sys.modules if m.startswith(engine)))\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, check=True
    ).stdout
    assert out.strip() == "[]"


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
