"""Every example in examples/ loads and steps: two steps at its own size, with its mass,
its particles and the domain kept, with what inlets brought and outlets let go (a renamed
key or a moved module that breaks an example fails here, not in a user's first run)."""

from pathlib import Path

import numpy as np
import pytest

import mpmflow

EXAMPLES = sorted((Path(__file__).resolve().parents[1] / "examples").glob("*.toml"))


def test_the_examples_are_all_found():
    assert len(EXAMPLES) >= 15


@pytest.mark.parametrize("path", EXAMPLES, ids=[p.stem for p in EXAMPLES])
def test_each_example_takes_two_steps(path):
    case = mpmflow.load_case(path)
    dt = case.time.dt if case.time.dt != "auto" else case.time.max_dt
    case = mpmflow.load_case(path, {"time.end": 2 * dt})
    sim = mpmflow.Simulation(case)
    mass, count = float(sim.particles.mass.sum()), sim.particles.count
    summary = sim.run()
    assert summary["status"] == "completed"
    assert sim.steps >= 2 and sim.time == pytest.approx(2 * dt, rel=1e-12)
    P = sim.particles
    into, out = sim.scheme.inflow, sim.scheme.outflow  # an inlet's water, an outlet's
    assert P.count == count + into.count - out.count
    assert float(P.mass.sum()) == pytest.approx(mass + into.mass - out.mass, rel=1e-12)
    assert into.count == 0 or case.inlets
    assert np.isfinite(P.x).all() and np.isfinite(P.v).all() and np.isfinite(P.pressure).all()
    size = np.asarray(case.domain.size)
    assert np.all(P.x >= 0.0) and np.all(P.x <= size)
