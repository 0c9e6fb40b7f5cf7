"""Property-based test of the settings that reach the physics: materials with parameters
at their extremes, and probes on walls, in corners, on obstacle faces and inside solids.
Every generated case runs its first steps or stops with a clean error (exit 2 for bad input,
3 for a documented run failure), never a traceback; the same rules and the same runner as
test_input_fuzz.py."""

import copy
import json

import hypothesis.strategies as st
import pytest
import tomllib
from hypothesis import HealthCheck, given, settings
from test_input_fuzz import BASE, _run_case, cap_steps, to_toml

from mpmflow import memory

CASES = 400

EXTREMES = [
    0.0,
    -1.0,
    5e-324,
    1e-300,
    1e-9,
    1e-3,
    1.0,
    50.0,
    1e3,
    1e5,
    1e8,
    1e12,
    1e30,
    1e308,
    float("inf"),
    float("nan"),
]
MODELS = {
    "newtonian": {"viscosity": 1.0},
    "herschel_bulkley": {
        "consistency": 1.0,
        "yield_stress": 50.0,
        "flow_index": 1.0,
        "max_viscosity": 1e5,
    },
    "mu_i": {
        "friction_static": 0.38,
        "friction_limit": 0.64,
        "inertial_number_ref": 0.28,
        "grain_diameter": 1e-3,
        "grain_density": 2450.0,
        "max_viscosity": 1e5,
    },
    "water": {},
}
SIZE = [0.1, 0.1]
OBSTACLES = [
    {"type": "box", "min": [0.06, 0.0], "max": [0.08, 0.02]},
    {"type": "disc", "centre": [0.07, 0.05], "radius": 0.012},
    {"type": "box", "min": [0.0, 0.0], "max": [0.03, 0.03]},
]  # in the body


def _along(draw, k):
    """A coordinate along axis k: on a wall, in a corner's reach, a grid line, inside,
    just outside."""
    side = SIZE[k]
    if draw(st.integers(0, 19)) == 0:
        return draw(st.sampled_from([-1e-9, side + 1e-9]))  # refused
    return draw(st.sampled_from([0.0, side, 1e-12, side - 1e-12, 0.02, 0.05, 0.07, 0.061, 0.0799]))


@st.composite
def physics_case(draw):
    data = json.loads(json.dumps(BASE))
    data["grid"]["spacing"] = 0.01  # the obstacles are two cells thick
    model = draw(st.sampled_from(sorted(MODELS)))
    material = {"model": model, "density": 1470.0 if model == "mu_i" else 1000.0, **MODELS[model]}
    if draw(st.booleans()):  # one parameter at an extreme, the others usual
        key = draw(st.sampled_from(list(MODELS[model]) + ["density"]))
        material[key] = draw(st.sampled_from(EXTREMES))
    data["material"] = material
    if draw(st.booleans()):
        data["domain"]["walls"] = "no_slip"
    if draw(st.booleans()):
        data["obstacles"] = copy.deepcopy(
            draw(st.lists(st.sampled_from(OBSTACLES), min_size=1, max_size=2))
        )
        data["bodies"][0]["around_obstacles"] = draw(st.booleans())
    probes = []
    for n in range(draw(st.integers(1, 4))):
        quantity = draw(st.sampled_from(["pressure", "level"]))
        probe = {
            "name": f"p{n}",
            "quantity": quantity,
            "position": [_along(draw, 0), _along(draw, 1)],
        }
        if quantity == "pressure":
            if draw(st.booleans()):
                probe["window"] = draw(st.sampled_from([1e-9, 0.001, 0.02, 0.1, 1.0, 1e300]))
            probe["estimate"] = draw(st.sampled_from(["fit", "mean"]))
        probes.append(probe)
    data["probes"] = probes
    if draw(st.booleans()):
        data["time"]["dt"] = draw(st.sampled_from([1e-4, 5e-4]))
    return to_toml(data)


@pytest.mark.filterwarnings("error")  # a numerical warning is a defect as a traceback is
@pytest.mark.slow
def test_materials_and_probes_run_or_fail_cleanly(monkeypatch):
    """The property over CASES cases, and a check that it was not vacuous: cases of every
    model ran and cases were refused."""
    budget = memory.PROGRAM + 8 * memory.MB
    monkeypatch.setattr(memory, "available", lambda: (budget, "the test's budget"))
    cap_steps(monkeypatch)
    monkeypatch.setenv("MPMFLOW_THREADS", "1")
    outcomes = {}

    @settings(
        max_examples=CASES,
        deadline=None,
        database=None,
        suppress_health_check=[HealthCheck.too_slow],
    )
    @given(text=physics_case())
    def one_case(text):
        code, err = _run_case(text)
        model = tomllib.loads(text)["material"]["model"]
        key = (model, "ran" if code in ("ran", 0) else code)
        outcomes[key] = outcomes.get(key, 0) + 1

    one_case()
    print(outcomes)
    assert sum(outcomes.values()) == CASES
    for model in MODELS:
        assert outcomes.get((model, "ran"), 0) >= 5, (model, outcomes)
    assert sum(v for (_, code), v in outcomes.items() if code == 2) >= 30, outcomes
