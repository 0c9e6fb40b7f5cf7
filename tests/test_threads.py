"""Results do not depend on the number of threads (the parallel kernels sum in a fixed order)."""

import numba
import numpy as np
import pytest
from conftest import EXAMPLES

from mpmflow import Simulation, load_case


def run(threads, settings):
    before = numba.get_num_threads()
    numba.set_num_threads(threads)
    try:
        case = load_case(EXAMPLES / "dam_break.toml", [*settings, "output.snapshots=false"])
        sim = Simulation(case)
        sim.run()
        return sim.particles
    finally:
        numba.set_num_threads(before)


@pytest.mark.parametrize("settings", [
    ["grid.spacing=0.01", "time.end=0.15"],  # through the wall impact
    # 7k pressure unknowns: above multigrid.PARALLEL_ROWS, so the solve's parallel loops
    # and the parallel Galerkin products run too
    ["grid.spacing=0.002", "time.dt=5e-4", "time.end=0.005"],
])
def test_dam_break_is_bit_identical_on_one_and_two_threads(settings):
    if numba.config.NUMBA_NUM_THREADS < 2:
        pytest.skip("one thread only")
    one, two = run(1, settings), run(2, settings)
    for field in ("x", "v", "pressure"):
        assert np.array_equal(getattr(one, field), getattr(two, field)), field
