"""Property-based test of the input handling: 500 random or mutated case files, each run
through the command line in-process. Every one must either run (its first steps) or stop
with a clean error: exit 2 for bad input, or exit 3 for a run the settings make fail
(a documented blow-up or solver message); never a traceback or another exit code.

Among the mutations: overlapping bodies, huge sizes (tiny grid spacings, vast domains, many
particles per cell) and endless end times; the machine's memory is replaced by a small
budget, so that the memory estimate refuses every case above it, as it refuses a case too
large for the real machine."""

import contextlib
import copy
import io
import json
import math
import tempfile
from pathlib import Path

import hypothesis.strategies as st
import pytest
from hypothesis import HealthCheck, given, settings

from mpmflow import case as case_module
from mpmflow import memory
from mpmflow.cli import main
from mpmflow.simulation import Simulation

STEPS = 5  # steps each accepted case runs before the test stops it

BASE = {
    "title": "fuzz",
    "domain": {"size": [0.1, 0.1], "walls": "slip"},
    "grid": {"spacing": 0.02},
    "bodies": [{"type": "box", "min": [0.0, 0.0], "max": [0.04, 0.06],
                "particles_per_cell": 2, "velocity": [0.0, 0.0], "initial_pressure": "zero"}],
    "material": {"density": 1000.0, "viscosity": 0.0, "bulk_modulus": 2.2e9},
    "physics": {"gravity": [0.0, -9.81]},
    "time": {"dt": 1e-3, "end": 3e-3, "safety_factor": 0.5},
    "output": {"interval": 1e-3, "snapshot_interval": 2e-3, "snapshots": True},
    "solver": {"scheme": "projection", "formulation": "mpmflow", "flip": 0.99,
               "max_iterations": 200, "tolerance": 1e-8, "max_speed": 100.0},
    "checkpoint": {"interval": 2e-3},
    "probes": [{"name": "p1", "quantity": "pressure", "position": [0.1, 0.01]},
               {"name": "h1", "quantity": "level", "position": [0.05, 0.0]}],
}
EXPLICIT = {"solver": {"scheme": "explicit"}, "material": {"bulk_modulus": 4e5},
            "time": {"dt": "auto"}}


# ----------------------------------------------------------------------- TOML writing
def _string(text):
    """A TOML basic string: quote, backslash and control characters escaped."""
    return '"' + "".join(f"\\u{ord(c):04x}" if ord(c) < 0x20 or ord(c) == 0x7F or c in '"\\'
                         else c for c in text) + '"'


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
    st.sampled_from([0, -1, 1, 0.0, -0.0, 1e308, -1e308, 5e-324, 1e-9, 1e9, 2**63 - 1,
                     float("nan"), float("inf"), float("-inf"), "auto", "", "box", "paper",
                     "explicit", "node", True, False, [], [1.0], [1.0, 2.0, 3.0],
                     ["a", "b"], {}, {"x": 1}]),
    st.floats(allow_nan=True, allow_infinity=True),
    st.integers(min_value=-(2**63), max_value=2**63 - 1),
    st.text(max_size=8),
    st.lists(st.floats(-1e3, 1e3), min_size=0, max_size=3),
)
VALID = {  # other allowed values, so that many mutated cases are accepted and run
    "walls": ["no_slip"], "particles_per_cell": [1, 3], "initial_pressure": ["hydrostatic"],
    "formulation": ["paper"], "free_surface": ["node"], "wall_flux": [False],
    "partial_cell_quadrature": ["particles"], "linear_solver": ["direct", "amg"],
    "flip": [0.0, 1.0], "density_correction": [0.0, 1.0], "velocity": [[0.5, -0.5]],
    "gravity": [[0.0, 0.0], [3.0, -9.81]], "snapshots": [False], "spacing": [0.01, 0.025],
    "max": [[0.1, 0.1]], "min": [[0.02, 0.03]], "end": [1e-3], "dt": [5e-4],
    "pressure_smoothing": ["none"], "max_speed": [1e-3], "quantity": ["level"],
    "position": [[0.0, 0.0], [0.1, 0.1]], "threads": [1, 2, "auto"],
}
HUGE = [("grid", "spacing", [1e-5, 1e-7, 1e-300]), ("domain", "size", [[1e6, 1e6], [1e300, 1.0]]),
        ("time", "end", [1e300, 1e12, 1e9, 1e30]), ("time", "dt", [1e-300, 1e-12]),
        ("output", "interval", [1e-300, 1e-9]), ("bodies.0", "particles_per_cell", [16])]
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
        data["bodies"].append({"min": lo, "max": [min(h, 0.1) for h in hi],
                               "particles_per_cell": draw(st.sampled_from([1, 2, 3]))})
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
            parent[last] = type(value)(value * factor) if math.isfinite(value * factor) \
                else value
        elif op in ("unknown", "typo") and isinstance(parent, dict):
            name = draw(st.text("abcdefghijklmnopqrstuvwxyz_", min_size=1, max_size=12)) \
                if op == "unknown" else draw(st.sampled_from(known)) + draw(
                    st.sampled_from(["s", "_", "x"]))
            parent[name] = copy.deepcopy(draw(scalars))
        else:
            parent[last] = copy.deepcopy(draw(scalars))
    return to_toml(data)


case_text = st.one_of(mutated_case(), mutated_case(), mutated_case(),
                      st.text(max_size=200),
                      st.text("[]=.\"',#\n abcdefgxyz0123456789-+e", max_size=200))


# ----------------------------------------------------------------------- the property
class Enough(BaseException):
    """The accepted case ran its first steps; the test stops it there."""


_ADVANCE = Simulation._advance


def _capped(self, dt, n):
    _ADVANCE(self, dt, min(n, STEPS - self.steps))
    if self.steps >= STEPS:
        raise Enough


def test_any_case_file_runs_or_fails_cleanly(monkeypatch):
    """The property over 500 case files, then a check that both accepted and refused cases
    were among them (the property was not vacuous). One test, so that the check does not
    depend on the order or selection of tests (-k, --lf, xdist, random order)."""
    # every accepted case stays small: the memory a run may use is the program's and 8 MB
    # more (about 30k particles or 50k nodes; the estimate refuses the rest as it refuses a
    # case larger than the machine), and it is stopped after STEPS steps
    budget = memory.PROGRAM + 8 * memory.MB
    monkeypatch.setattr(memory, "available", lambda: (budget, "the test's budget"))
    monkeypatch.setattr(Simulation, "_advance", _capped)
    monkeypatch.setenv("MPMFLOW_THREADS", "1")  # no sampling of the machine's load
    outcomes = {}

    @settings(max_examples=500, deadline=None, database=None,
              suppress_health_check=[HealthCheck.too_slow])
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


REFUSALS = {"overlap": "Bodies may touch but not overlap", "memory": "of memory",
            "steps": "a run can take"}


def _run_case(text):
    """Run one case file through the command line; check the outcome; return it and the
    message."""
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "case.toml"
        path.write_text(text)
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
        assert any(cause in err for cause in ("The run blew up", "did not converge",
                                              "became unstable", "is singular")), err
    return code, err


@pytest.mark.parametrize("key, value, words", [
    ("grid.spacing", 5e-324, "cells along a side of the domain"),
    ("material.density", 5e-324, "too small for a floating-point number"),
    ("checkpoint.interval", 5e-324, None),  # every output: runs
    ("output.snapshot_interval", 5e-324, None),
])
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
