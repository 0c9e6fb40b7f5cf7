"""time.dt = "auto" with the projection scheme: each step set by the particles' speeds
(State.advance_span), within time.max_dt, landing on every output time exactly."""

import numpy as np
import pytest
from conftest import EXAMPLES

from mpmflow import Simulation, load_case

RHO, G = 1000.0, 9.81


def test_a_column_at_rest_takes_the_longest_step_and_stays_exact():
    """At rest the fastest particle is still, so every step is time.max_dt; the column stays
    exact to the solve's tolerance, as with a fixed step."""
    case = load_case(
        EXAMPLES / "hydrostatic.toml",
        [
            "bodies.0.max=[0.1, 0.2]",
            "time.dt=auto",
            "time.max_dt=5e-3",
            "time.end=0.2",
            "output.snapshots=false",
        ],
    )
    sim = Simulation(case)
    summary = sim.run()
    assert sim.steps == 40  # 0.2 s in steps of 5 ms
    assert summary["adaptive_steps"]["shortest"] == pytest.approx(5e-3)
    P = sim.particles
    exact = RHO * G * (0.2 - P.x[:, 1])
    err = np.sqrt(np.sum((P.pressure - exact) ** 2) / np.sum(exact**2))
    assert err < 100 * case.solver.tolerance
    assert np.nanmax(sim.series("max_speed")) < 1e-8


@pytest.mark.slow
def test_the_steps_follow_the_courant_number_and_land_on_every_output(tmp_path):
    """A dam break: no step is longer than time.courant h / max |v| (checked through the
    summary's shortest step against the fastest particle of the run), the output rows fall
    on multiples of output.interval exactly, and halving the Courant number takes more
    steps."""
    steps = {}
    for courant in (1.0, 0.5):
        out = tmp_path / f"co{courant}"
        case = load_case(
            EXAMPLES / "dam_break.toml",
            [
                "grid.spacing=0.008",
                "time.end=0.3",
                "time.dt=auto",
                f"time.courant={courant}",
                "output.snapshots=false",
            ],
        )
        sim = Simulation(case, out_dir=out)
        summary = sim.run()
        assert summary["status"] == "completed"
        steps[courant] = sim.steps
        times = np.loadtxt(out / "timeseries.csv", delimiter=",", skiprows=1, usecols=0)
        assert np.array_equal(times, np.round(times / 0.01) * 0.01)
        fastest = np.nanmax(sim.series("max_speed"))
        shortest = summary["adaptive_steps"]["shortest"]
        # the fastest particle seen at an output bounds the speeds some step started from
        assert shortest <= courant * 0.008 / fastest * (1 + 1e-9)
        # (the last step of a span is the rest of it, which rounding can leave 1 ulp long)
        assert summary["adaptive_steps"]["longest"] <= case.time.max_dt * (1 + 1e-12)
    assert steps[0.5] > 1.5 * steps[1.0]


def test_auto_with_a_python_solver_follows_the_multigrid():
    """A solver from Python (SciPy's direct solve) plugs into the core's step, adaptive steps
    included: the same steps as the core's multigrid, and the same flow to the solvers'
    tolerance (1e-8 relative residual; measured 9e-12 m and 7e-7 Pa apart). A solver that
    were not plugged in would leave the column in free fall at zero pressure."""
    runs = {}
    for solver in ("multigrid", "direct"):
        case = load_case(
            EXAMPLES / "dam_break.toml",
            [
                "time.dt=auto",
                f"solver.linear_solver={solver}",
                "grid.spacing=0.01",
                "time.end=0.1",
                "output.snapshots=false",
            ],
        )
        sim = Simulation(case)
        sim.run()
        runs[solver] = sim.steps, np.array(sim.particles.x), np.array(sim.particles.pressure)
    (steps_mg, x_mg, p_mg), (steps_d, x_d, p_d) = runs["multigrid"], runs["direct"]
    assert steps_d == steps_mg
    assert np.abs(x_d - x_mg).max() <= 1e-9  # m
    assert np.abs(p_d - p_mg).max() <= 1e-6 * np.abs(p_mg).max()


def test_the_schedule_rules():
    """The step's schedule as the core writes it once (src/core/step.hpp) for every loop."""
    from mpmflow import state

    # Courant: 1 m/s on 0.01 m at C = 0.5 gives 5 ms; nothing moving gives dt_max
    assert state.adaptive_dt(1.0, 0.5, 0.01, 1.0, 1.0) == 0.005
    assert state.adaptive_dt(0.0, 0.5, 0.01, 2e-3, 1.0) == 2e-3
    # the rest of the span: taken whole when it fits, halved when a second step would
    # leave a sliver (6 ms left, 5 ms steps: two of 3 ms)
    assert state.adaptive_dt(1.0, 0.5, 0.01, 1.0, 0.004) == 0.004
    assert state.adaptive_dt(1.0, 0.5, 0.01, 1.0, 0.006) == 0.003
    assert state.adaptive_dt(1.0, 0.5, 0.01, 1.0, 0.011) == 0.005
    # the volume correction: every 3rd step; after 2 ms of flow
    assert [state.volume_due_fixed(k, 3) for k in range(1, 7)] == [
        False,
        False,
        True,
        False,
        False,
        True,
    ]
    assert not state.volume_due_fixed(3, 0)
    since, due = 0.0, []
    for _ in range(5):
        d, since = state.volume_due_adaptive(since, 1e-3, 1.0, 2e-3)
        due.append(d)
    assert due == [False, True, False, True, False] and since == 1e-3
    assert state.volume_due_adaptive(0.0, 1.0, 0.0, 2e-3) == (False, 0.0)
