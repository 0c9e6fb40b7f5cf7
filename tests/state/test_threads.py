"""Threads: results do not depend on their number (the parallel kernels sum in a fixed
order), and "auto" leaves to other programs the cores they keep busy."""

import os
import subprocess
import sys
import time

import numpy as np
import pytest
from conftest import EXAMPLES

from mpmflow import Simulation, load_case, state
from mpmflow import threads as threads_module
from mpmflow.errors import CaseError


def run(threads, settings):
    case = load_case(
        EXAMPLES / "dam_break.toml",
        [*settings, "output.snapshots=false", f"execution.threads={threads}"],
    )
    sim = Simulation(case)
    summary = sim.run()
    assert [c["threads"] for c in summary["threads"]["changes"]] == [threads]
    return sim


@pytest.mark.parametrize(
    "settings",
    [
        ["grid.spacing=0.01", "time.end=0.15"],  # through the wall impact
        # 7k pressure unknowns: above multigrid.PARALLEL_ROWS, so the solve's parallel loops
        # and the parallel Galerkin products run too
        ["grid.spacing=0.002", "time.dt=5e-4", "time.end=0.005"],
        # APIC's transfers (100k particles: parallel strips and chunks)
        ["grid.spacing=0.002", "time.dt=5e-4", "time.end=0.005", "solver.transfer=apic"],
        # x periodic (the tank is 0.576 m = 144 cells of 0.004 m: the folds, the wrapped
        # stencils and the multigrid's periodic levels on both thread counts)
        ["domain.size=[0.576, 0.44]", "domain.periodic=[true, false]", "time.end=0.05"],
    ],
)
@pytest.mark.slow
def test_dam_break_is_bit_identical_on_one_and_two_threads(settings):
    if state.POOL < 2:
        pytest.skip("one thread only")
    one, two = run(1, settings), run(2, settings)
    for field in ("x", "v", "pressure"):
        assert np.array_equal(getattr(one.particles, field), getattr(two.particles, field)), field
    # a diagnostic summed over strips (the pressure noise's nodal sums) and chunks
    assert one.measure()["pressure_noise"] == two.measure()["pressure_noise"]


def test_the_cores_threads_are_given_back_after_a_run():
    before = state.max_threads()
    run(1, ["grid.spacing=0.02", "time.end=0.01"])
    assert state.max_threads() == before


def test_the_setting_and_the_environment_variable(monkeypatch):
    monkeypatch.setenv(threads_module.ENV, "1")
    assert threads_module.setting_from("auto") == ("fixed", 1)
    assert (
        threads_module.setting_from(2 if state.POOL >= 2 else 1)[0] == "fixed"
    )  # a number in the case wins over the variable
    monkeypatch.setenv(threads_module.ENV, "many")
    with pytest.raises(CaseError, match="MPMFLOW_THREADS = 'many' is not a number"):
        threads_module.setting_from("auto")
    monkeypatch.delenv(threads_module.ENV)
    assert threads_module.setting_from("auto") == ("auto", None)
    too_many = state.POOL + 1
    with pytest.raises(CaseError, match=f"execution.threads = {too_many} is more threads"):
        threads_module.setting_from(too_many)


def test_auto_counts_the_cores_others_keep_busy(monkeypatch):
    """The choice from the measured load: a core counts as free when 3/4 of it is idle."""
    gov = threads_module.ThreadGovernor("auto")
    gov.cores, gov.limit = 2, 2
    assert [gov.choose(x) for x in (0.0, 0.2, 0.3, 1.0, 1.2, 2.0)] == [2, 2, 1, 1, 1, 0]
    gov.take(gov.choose(2.5), 0.0, 2.5)  # never below one thread
    assert gov.threads == 1
    gov.stop()


@pytest.mark.skipif(
    not os.path.exists("/proc/stat") or len(os.sched_getaffinity(0)) < 2 or state.POOL < 2,
    reason="needs Linux and 2 cores",
)
@pytest.mark.slow
def test_auto_runs_on_fewer_threads_beside_busy_programs():
    """With a busy process on every core but one, "auto" starts on one thread, whatever
    else the machine is doing (the other engineer's tests may add load: fewer free cores
    only lower the choice)."""
    cores = min(len(os.sched_getaffinity(0)), state.POOL)
    busy = [subprocess.Popen([sys.executable, "-c", "while True: pass"]) for _ in range(cores - 1)]
    try:
        time.sleep(0.3)
        gov = threads_module.ThreadGovernor("auto")
        gov.start()
        assert gov.threads == 1, gov.changes
        time.sleep(1.1)
        gov.update(1.0)  # measured over the last second: still one
        assert gov.threads == 1, gov.changes
        gov.stop()
    finally:
        for p in busy:
            p.kill()
            p.wait()
