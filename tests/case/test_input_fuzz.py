"""Property-based test of the input handling: 500 random or mutated case files, and 600 3D
cases with generated mesh files as bodies and obstacles, each run through the command line
in-process. Every one must either run (its first steps) or stop
with a clean error: exit 2 for bad input, or exit 3 for a run the settings make fail
(a documented blow-up or solver message); never a traceback or another exit code.

Among the mutations: overlapping bodies, huge sizes (tiny grid spacings, vast domains, many
particles per cell) and endless end times; the machine's memory is replaced by a small
budget, so that the memory estimate refuses every case above it, as it refuses a case too
large for the real machine.

The mesh files are binary and ASCII STL and OBJ, written here byte by byte: names in odd
encodings, wrong binary triangle counts, cut files, degenerate (zero-area) and flipped
triangles, open and flat meshes, non-numbers, at tiny and huge scales."""

import contextlib
import copy
import io
import json
import logging
import math
import struct
import tempfile
import warnings
from pathlib import Path

import hypothesis.strategies as st
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings

from mpmflow import case as case_module
from mpmflow import memory
from mpmflow.cli import main

STEPS = 5  # steps each accepted case runs before the test stops it

BASE = {
    "title": "fuzz",
    "domain": {"size": [0.1, 0.1], "walls": "slip"},
    "grid": {"spacing": 0.02},
    "bodies": [
        {
            "type": "box",
            "min": [0.0, 0.0],
            "max": [0.04, 0.06],
            "particles_per_cell": 2,
            "velocity": [0.0, 0.0],
            "initial_pressure": "zero",
        }
    ],
    "material": {"density": 1000.0, "viscosity": 0.0, "bulk_modulus": 2.2e9},
    "physics": {"gravity": [0.0, -9.81]},
    "time": {"dt": 1e-3, "end": 3e-3, "safety_factor": 0.5},
    "output": {"interval": 1e-3, "snapshot_interval": 2e-3, "snapshots": True},
    "solver": {
        "scheme": "projection",
        "formulation": "mpmflow",
        "flip": 0.99,
        "max_iterations": 200,
        "tolerance": 1e-8,
        "max_speed": 100.0,
    },
    "checkpoint": {"interval": 2e-3},
    "probes": [
        {"name": "p1", "quantity": "pressure", "position": [0.1, 0.01]},
        {"name": "h1", "quantity": "level", "position": [0.05, 0.0]},
    ],
}
EXPLICIT = {
    "solver": {"scheme": "explicit"},
    "material": {"bulk_modulus": 4e5},
    "time": {"dt": "auto"},
}


# ----------------------------------------------------------------------- TOML writing
def _string(text):
    """A TOML basic string: quote, backslash and control characters escaped."""
    return (
        '"'
        + "".join(
            f"\\u{ord(c):04x}" if ord(c) < 0x20 or ord(c) == 0x7F or c in '"\\' else c for c in text
        )
        + '"'
    )


def _value(v):
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, float):
        if math.isnan(v):
            return "nan"
        if math.isinf(v):
            return "inf" if v > 0 else "-inf"
        return repr(v)
    if isinstance(v, int):
        return str(v)
    if isinstance(v, str):
        return _string(v)
    if isinstance(v, list):
        return "[" + ", ".join(_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{" + ", ".join(f"{_string(k)} = {_value(x)}" for k, x in v.items()) + "}"
    raise TypeError(type(v))


def to_toml(data):
    lines, tables = [], []
    for key, value in data.items():
        if isinstance(value, dict):
            tables.append(f"[{_string(key)}]")
            tables += [f"{_string(k)} = {_value(v)}" for k, v in value.items()]
        elif isinstance(value, list) and value and all(isinstance(x, dict) for x in value):
            for item in value:
                tables.append(f"[[{_string(key)}]]")
                tables += [f"{_string(k)} = {_value(v)}" for k, v in item.items()]
        else:
            lines.append(f"{_string(key)} = {_value(value)}")
    return "\n".join(lines + tables) + "\n"


# ----------------------------------------------------------------------- strategies
def _paths(data, prefix=()):
    """Every place in the case dict: (path, value)."""
    out = []
    items = data.items() if isinstance(data, dict) else enumerate(data)
    for key, value in items:
        out.append((prefix + (key,), value))
        if isinstance(value, (dict, list)):
            out += _paths(value, prefix + (key,))
    return out


scalars = st.one_of(
    st.sampled_from(
        [
            0,
            -1,
            1,
            0.0,
            -0.0,
            1e308,
            -1e308,
            5e-324,
            1e-9,
            1e9,
            2**63 - 1,
            float("nan"),
            float("inf"),
            float("-inf"),
            "auto",
            "",
            "box",
            "paper",
            "explicit",
            "node",
            True,
            False,
            [],
            [1.0],
            [1.0, 2.0, 3.0],
            ["a", "b"],
            {},
            {"x": 1},
        ]
    ),
    st.floats(allow_nan=True, allow_infinity=True),
    st.integers(min_value=-(2**63), max_value=2**63 - 1),
    st.text(max_size=8),
    st.lists(st.floats(-1e3, 1e3), min_size=0, max_size=3),
)
VALID = {  # other allowed values, so that many mutated cases are accepted and run
    "walls": ["no_slip", {"y_min": "no_slip", "x": "slip"}],
    "particles_per_cell": [1, 3],
    "initial_pressure": ["hydrostatic"],
    "formulation": ["paper"],
    "free_surface": ["node"],
    "wall_flux": [False],
    "partial_cell_quadrature": ["particles"],
    "linear_solver": ["direct", "amg"],
    "flip": [0.0, 1.0],
    "density_correction": [0.0, 1.0],
    "velocity": [[0.5, -0.5]],
    "gravity": [[0.0, 0.0], [3.0, -9.81]],
    "snapshots": [False],
    "spacing": [0.01, 0.025],
    "max": [[0.1, 0.1]],
    "min": [[0.02, 0.03]],
    "end": [1e-3],
    "dt": [5e-4],
    "pressure_smoothing": ["none"],
    "max_speed": [1e-3],
    "quantity": ["level"],
    "position": [[0.0, 0.0], [0.1, 0.1]],
    "threads": [1, 2, "auto"],
}
HUGE = [
    ("grid", "spacing", [1e-5, 1e-7, 1e-300]),
    ("domain", "size", [[1e6, 1e6], [1e300, 1.0]]),
    ("time", "end", [1e300, 1e12, 1e9, 1e30]),
    ("time", "dt", [1e-300, 1e-12]),
    ("output", "interval", [1e-300, 1e-9]),
    ("bodies.0", "particles_per_cell", [16]),
]
known = sorted({p.split(".")[-1] for p in case_module.KNOWN_KEYS} | set(BASE))


@st.composite
def mutated_case(draw):
    data = json.loads(json.dumps(BASE))
    if draw(st.booleans()):
        for section, values in EXPLICIT.items():
            data[section].update(values)
    for _ in range(draw(st.integers(0, 3))):  # other allowed values
        choices = [(path, v) for path, v in _paths(data) if path[-1] in VALID]
        path, _ = draw(st.sampled_from(choices))
        parent = data
        for key in path[:-1]:
            parent = parent[key]
        parent[path[-1]] = copy.deepcopy(draw(st.sampled_from(VALID[path[-1]])))
    if draw(st.integers(0, 4)) == 0:  # a second body, often overlapping the first
        lo = [draw(st.sampled_from([0.0, 0.02, 0.04, 0.06])) for _ in range(2)]
        hi = [a + draw(st.sampled_from([0.02, 0.04, 0.06])) for a in lo]
        data["bodies"].append(
            {
                "min": lo,
                "max": [min(h, 0.1) for h in hi],
                "particles_per_cell": draw(st.sampled_from([1, 2, 3])),
            }
        )
    if draw(st.integers(0, 4)) == 0:  # a huge size or an endless end time
        section, key, values = draw(st.sampled_from(HUGE))
        parent = data["bodies"][0] if section == "bodies.0" else data[section]
        parent[key] = copy.deepcopy(draw(st.sampled_from(values)))
    for _ in range(draw(st.integers(0, 3))):  # anything
        path, value = draw(st.sampled_from(_paths(data)))
        *head, last = path
        parent = data
        for key in head:
            parent = parent[key]
        op = draw(st.sampled_from(["delete", "replace", "scale", "unknown", "typo"]))
        if op == "delete":
            del parent[last]
        elif op == "scale" and isinstance(value, (int, float)) and not isinstance(value, bool):
            factor = draw(st.sampled_from([-1, 0, 0.1, 0.5, 2, 10, 1e6]))
            parent[last] = type(value)(value * factor) if math.isfinite(value * factor) else value
        elif op in ("unknown", "typo") and isinstance(parent, dict):
            name = (
                draw(st.text("abcdefghijklmnopqrstuvwxyz_", min_size=1, max_size=12))
                if op == "unknown"
                else draw(st.sampled_from(known)) + draw(st.sampled_from(["s", "_", "x"]))
            )
            parent[name] = copy.deepcopy(draw(scalars))
        else:
            parent[last] = copy.deepcopy(draw(scalars))
    return to_toml(data)


case_text = st.one_of(
    mutated_case(),
    mutated_case(),
    mutated_case(),
    st.text(max_size=200),
    st.text("[]=.\"',#\n abcdefgxyz0123456789-+e", max_size=200),
)


# ----------------------------------------------------------------------- the property
class Enough(BaseException):
    """The accepted case ran its first steps; the test stops it there."""


def cap_steps(monkeypatch):
    """Every scheme stops the run (Enough) once it has taken STEPS steps: the chunk that
    reaches them is cut short (the blow-up guard acts on it as after any chunk), and the
    next chunk stops the run before it steps."""
    from mpmflow import schemes

    for cls in list(schemes.registry().values()):
        advance = cls.advance

        def capped(self, dt, n, where, advance=advance):
            done = getattr(self, "fuzz_steps", 0)
            if done >= STEPS:
                raise Enough
            self.fuzz_steps = done + min(n, STEPS - done)
            return advance(self, dt, min(n, STEPS - done), where)

        monkeypatch.setattr(cls, "advance", capped)


@pytest.mark.slow
def test_any_case_file_runs_or_fails_cleanly(monkeypatch):
    """The property over 500 case files, then a check that both accepted and refused cases
    were among them (the property was not vacuous). One test, so that the check does not
    depend on the order or selection of tests (-k, --lf, xdist, random order)."""
    # every accepted case stays small: the memory a run may use is the program's and 8 MB
    # more (about 30k particles or 50k nodes; the estimate refuses the rest as it refuses a
    # case larger than the machine), and it is stopped after STEPS steps
    budget = memory.PROGRAM + 8 * memory.MB
    monkeypatch.setattr(memory, "available", lambda: (budget, "the test's budget"))
    cap_steps(monkeypatch)
    monkeypatch.setenv("MPMFLOW_THREADS", "1")  # no sampling of the machine's load
    outcomes = {}

    @settings(
        max_examples=500,
        deadline=None,
        database=None,
        derandomize=True,  # the same 500 cases on every run: its counts below may not vary
        suppress_health_check=[HealthCheck.too_slow],
    )
    @given(text=case_text)
    def one_case(text):
        code, err = _run_case(text)
        outcomes[code] = outcomes.get(code, 0) + 1
        for kind, words in REFUSALS.items():
            if code == 2 and words in err:
                outcomes[kind] = outcomes.get(kind, 0) + 1

    one_case()
    print(outcomes)
    assert sum(v for k, v in outcomes.items() if not isinstance(k, str) or k == "ran") >= 500
    assert outcomes.get("ran", 0) + outcomes.get(0, 0) >= 25 and outcomes.get(2, 0) >= 100
    # the new refusals were reached, each with its own message
    for kind in ("overlap", "memory", "steps"):
        assert outcomes.get(kind, 0) >= 3, (kind, outcomes)


REFUSALS = {
    "overlap": "Bodies may touch but not overlap",
    "memory": "of memory",
    "steps": "a run can take",
}


def _run_case(text, files=None):
    """Run one case file through the command line (``files``: {name: bytes} written beside
    it, None for a folder); check the outcome; return it and the message."""
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "case.toml"
        path.write_text(text)
        for name, data in (files or {}).items():
            if data is None:
                (Path(tmp) / name).mkdir()  # a folder where a file is expected
            else:
                (Path(tmp) / name).write_bytes(data)
        err = io.StringIO()
        with contextlib.redirect_stderr(err):
            try:
                code = main(["run", str(path), "--out", str(Path(tmp) / "out"), "-q"])
            except Enough:
                code = "ran"
        err = err.getvalue()
    assert "Traceback" not in err
    assert code in ("ran", 0, 2, 3), (code, err, text)
    if code in (2, 3):  # the error is one line, after the notes the run printed
        lines = [line for line in err.splitlines() if not line.startswith("mpmflow: note: ")]
        assert len(lines) == 1 and lines[0].startswith("mpmflow: error: "), (err, text)
    if code == 3:
        assert any(
            cause in err
            for cause in (
                "The run blew up",
                "did not converge",
                "became unstable",
                "is singular",
                "could not be set up",
            )
        ), err
    return code, err


@pytest.mark.parametrize(
    "key, value, words",
    [
        ("grid.spacing", 5e-324, "cells along a side of the domain"),
        # (refused by its range since issue 40: 1 to 1e5 kg/m^3)
        ("material.density", 5e-324, "`material.density` = 5e-324 is not allowed"),
        ("checkpoint.interval", 5e-324, None),  # every output: runs
        ("output.snapshot_interval", 5e-324, None),
    ],
)
def test_subnormal_settings_are_refused_or_run(key, value, words):
    """The three subnormal values the fuzzing above found on a clean clone (a traceback each:
    an infinite cell count, particles of zero mass, an infinite checkpoint index), and the
    snapshot interval that shares the last's arithmetic."""
    data = copy.deepcopy(BASE)
    section, name = key.split(".")
    data[section][name] = value
    code, err = _run_case(to_toml(data))
    if words is None:
        assert code in ("ran", 0), err
    else:
        assert code == 2 and words in err, err


# ----------------------------------------------------------------------- mesh files
MESH_CASES = 600
MESH_STEPS_CASE = {
    "title": "mesh fuzz",
    "domain": {"size": [0.2, 0.2, 0.2], "walls": "slip"},
    "grid": {"spacing": 0.04},
    "bodies": [
        {
            "type": "box",
            "min": [0.0, 0.0, 0.0],
            "max": [0.2, 0.2, 0.08],
            "particles_per_cell": 1,
            "around_obstacles": True,
        }
    ],
    "physics": {"gravity": [0.0, 0.0, -9.81]},
    "time": {"dt": 1e-3, "end": 3e-3},
    "output": {"interval": 1e-3, "snapshots": False},
    "solver": {"scheme": "projection"},
}
SCALES = [0.1, 0.1, 0.12, 0.05, 0.001, 1e-6, 1.0, 1000.0, 1e-300, 1e300, 5e-324]
TRANSLATES = [
    [0.05, 0.05, 0.09],
    [0.05, 0.05, 0.09],
    [0.04, 0.06, 0.1],
    [0.0, 0.0, 0.0],
    [-1.0, 0.05, 0.1],
    [1e300, 0.0, 0.0],
]


def _solids():
    """Closed, outward-facing triangle soups in the unit box: (n, 3, 3) arrays."""
    import trimesh

    cube = trimesh.creation.box(extents=[1, 1, 1])
    ico = trimesh.creation.icosphere(subdivisions=1, radius=0.5)
    tet = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=float)
    return [
        cube.vertices[cube.faces] + 0.5,
        ico.vertices[ico.faces] + 0.5,
        tet[[[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]],
    ]


SOLIDS = _solids()
NAMES = ["cube", "Würfel", "", "名前", "a b\tc", "solid", "x" * 300]
ENCODINGS = ["utf-8", "latin-1", "utf-16", "utf-8-sig", "cp1252", "shift_jis"]


@st.composite
def triangles(draw):
    """A soup of triangles: a closed solid, or one broken in some way."""
    tri = SOLIDS[draw(st.integers(0, len(SOLIDS) - 1))].copy()
    for _ in range(draw(st.sampled_from([0, 0, 0, 1, 2]))):  # most files are sound
        k = draw(st.integers(0, len(tri) - 1))
        op = draw(
            st.sampled_from(
                [
                    "drop",
                    "double",
                    "flip",
                    "collapse",
                    "sliver",
                    "nan",
                    "inf",
                    "huge",
                    "flatten",
                    "inside_out",
                    "jitter",
                ]
            )
        )
        if op == "drop":  # an open mesh
            tri = np.delete(tri, k, axis=0)
        elif op == "double":
            tri = np.concatenate([tri, tri[k : k + 1]])
        elif op == "flip":  # one triangle against its neighbours
            tri[k] = tri[k, ::-1]
        elif op == "collapse":  # a zero-area triangle with a repeated corner
            tri[k, 1] = tri[k, 0]
        elif op == "sliver":  # a zero-area triangle with distinct corners
            tri[k, 2] = 0.5 * (tri[k, 0] + tri[k, 1])
        elif op in ("nan", "inf", "huge"):
            tri[k, 0, 0] = {"nan": np.nan, "inf": np.inf, "huge": 3e38}[op]
        elif op == "flatten":
            tri[..., 2] = 0.0
        elif op == "inside_out":
            tri = tri[:, ::-1]
        else:
            tri = tri + draw(st.sampled_from([1e-9, 1e-3]))
        if not len(tri):
            break
    return tri


def _stl_binary(tri, count, header):
    data = [header[:80].ljust(80, b"\0"), struct.pack("<I", count % 2**32)]
    with np.errstate(over="ignore"):  # huge coordinates become float32 inf, as intended
        data += [
            struct.pack("<12fH", 0.0, 0.0, 1.0, *np.ravel(t).astype(np.float32), 0) for t in tri
        ]
    return b"".join(data)


def _stl_ascii(tri, name, newline):
    lines = [f"solid {name}"]
    for t in tri:
        lines += ["  facet normal 0 0 1", "    outer loop"]
        lines += [f"      vertex {x:.9g} {y:.9g} {z:.9g}" for x, y, z in t]
        lines += ["    endloop", "  endfacet"]
    return newline.join(lines + [f"endsolid {name}", ""])


def _obj(tri, name, newline):
    lines = [f"# {name}", f"o {name}"] + [
        f"v {x:.9g} {y:.9g} {z:.9g}" for x, y, z in tri.reshape(-1, 3)
    ]
    lines += [f"f {3 * k + 1} {3 * k + 2} {3 * k + 3}" for k in range(len(tri))]
    return newline.join(lines + [""])


@st.composite
def mesh_file(draw):
    """(file name, bytes or None for a folder): a mesh file in some format, possibly
    damaged."""
    sound = draw(st.booleans())  # half the files are sound, in some format and encoding
    tri = SOLIDS[draw(st.integers(0, len(SOLIDS) - 1))] if sound else draw(triangles())
    kind = draw(st.sampled_from(["binary", "ascii", "obj"] + ([] if sound else ["odd"])))
    name = draw(st.sampled_from(NAMES))
    encoding = draw(st.sampled_from(ENCODINGS))
    newline = draw(st.sampled_from(["\n", "\r\n"]))
    if kind == "binary" and sound:
        return "mesh.stl", _stl_binary(tri, len(tri), name.encode("utf-8"))
    if kind == "binary":
        count = len(tri) + draw(st.sampled_from([0, 0, 0, 1, -1, 7, -len(tri), 2**31]))
        header = draw(st.sampled_from([b"", b"solid cube", name.encode("utf-8")]))
        data = _stl_binary(tri, count, header)
        cut = draw(st.sampled_from([0] * 6 + [1, 7, 50, 51]))
        data = data[: len(data) - cut] + draw(st.sampled_from([b""] * 6 + [b"\0" * 50, b"junk"]))
        return "mesh.stl", data
    if kind in ("ascii", "obj"):
        text = (_stl_ascii if kind == "ascii" else _obj)(tri, name, newline)
        data = text.encode(encoding, errors="replace")
        if not sound and draw(st.booleans()):
            data = data[: draw(st.integers(0, len(data)))]  # a file cut short
        return "mesh." + ("stl" if kind == "ascii" else "obj"), data
    return draw(
        st.sampled_from(
            [
                ("mesh.stl", b""),
                ("mesh.stl", None),
                ("mesh.ply", b"ply"),
                ("mesh.obj", b"\xff\xfe\0\0garbage"),
                ("mesh.STL", _stl_binary(SOLIDS[0], 12, b"upper case")),
                ("mesh.stl", bytes(range(256)) * 3),
            ]
        )
    )


@st.composite
def mesh_case(draw):
    data = json.loads(json.dumps(MESH_STEPS_CASE))
    name, content = draw(mesh_file())
    table = {
        "type": "mesh",
        "path": name,
        "scale": draw(st.sampled_from(SCALES)),
        "translate": draw(st.sampled_from(TRANSLATES)),
    }
    if draw(st.booleans()):
        table["particles_per_cell"] = draw(st.sampled_from([1, 2, 3]))
        data["bodies"].append(table)
        if draw(st.integers(0, 3)) == 0:  # the mesh alone
            del data["bodies"][0]
    else:
        data["obstacles"] = [table]
    return to_toml(data), {name: content}


class _Records(logging.Handler):
    """The warnings a library logs (trimesh logs to the "trimesh" logger)."""

    def __init__(self):
        super().__init__(logging.WARNING)
        self.records = []

    def emit(self, record):
        self.records.append(record)


@pytest.mark.slow
def test_any_mesh_case_runs_or_fails_cleanly(monkeypatch):
    """600 3D cases with a generated mesh file as a body or an obstacle: each runs its first
    steps or stops with a clean error (exit 2, naming the key of the mesh when the file is
    at fault; or 3), never a traceback, a Python warning or a library's logged warning.
    About 10 s on a 2-core machine. (A mesh in the corner at [0, 0, 0] once blew up at step
    2 with exit 3: a particle seeded in the corner cell the wall shift closes, where phi is
    flat, was pushed out along a round-off gradient; tests/test_obstacles.py keeps that
    case.)"""
    budget = memory.PROGRAM + 8 * memory.MB
    monkeypatch.setattr(memory, "available", lambda: (budget, "the test's budget"))
    cap_steps(monkeypatch)
    monkeypatch.setenv("MPMFLOW_THREADS", "1")
    logs = _Records()
    logging.getLogger().addHandler(logs)
    outcomes = {}

    @settings(
        max_examples=MESH_CASES,
        deadline=None,
        database=None,
        suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
    )
    @given(case=mesh_case())
    def one_case(case):
        text, files = case
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            code, err = _run_case(text, files)
        assert not caught, ([str(w.message) for w in caught], text)
        assert not logs.records, ([r.getMessage() for r in logs.records], text)
        if code == 2 and ".path = " in err:
            assert any(
                f"{k}.path = 'mesh." in err for k in ("bodies.0", "bodies.1", "obstacles.0")
            ), err
        outcomes[code] = outcomes.get(code, 0) + 1

    try:
        one_case()
    finally:
        logging.getLogger().removeHandler(logs)
    print(outcomes)
    assert sum(outcomes.values()) >= MESH_CASES
    ran = outcomes.get("ran", 0) + outcomes.get(0, 0)
    assert ran >= MESH_CASES // 12 and outcomes.get(2, 0) >= MESH_CASES // 3, outcomes


@pytest.mark.parametrize("key", ["solver.flip", "solver.volume_correction", "solver.wall_flux"])
def test_none_for_a_preset_solver_key_is_a_clear_error(key):
    """The keys a formulation presets start as None in the schema; None given in Python is
    refused with the key's name, not taken as a value that fails inside the step."""
    from conftest import EXAMPLES

    from mpmflow import CaseError, load_case

    with pytest.raises(CaseError, match=f"{key} = None is not a value"):
        load_case(EXAMPLES / "dam_break.toml", {key: None})
