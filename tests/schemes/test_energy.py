"""Energy of an inviscid flow in closed walls: it may be lost, never gained (docs/method.md,
"Energy"). The column at rest stays exact whichever surface quadrature is used."""

import numpy as np
import pytest
from conftest import EXAMPLES

from mpmflow import Simulation, load_case

EARLIER = [
    "solver.volume_correction=0",
    "solver.density_correction=0.2",
    "solver.sparse_cell_threshold=0.2",
    "solver.surface_quadrature=gauss",
]


@pytest.mark.parametrize("surface", ["divergence", "consistent", "gauss"])
def test_column_at_rest_is_exact_with_every_surface_quadrature(surface):
    case = load_case(
        EXAMPLES / "hydrostatic.toml",
        ["output.snapshots=false", "time.end=0.3", f"solver.surface_quadrature={surface}"],
    )
    sim = Simulation(case)
    sim.run()
    assert np.nanmax(sim.series("max_speed")) < 1e-8
    P = sim.particles
    exact = case.material.density * 9.81 * (0.195 - P.x[:, 1])
    assert np.abs(P.pressure - exact).max() < 1e-6 * exact.max()


def _sloshing_energy(settings, end=3.0):
    case = load_case(
        EXAMPLES / "sloshing.toml", ["output.snapshots=false", f"time.end={end}", *settings]
    )
    sim = Simulation(case)
    sim.run()
    e = sim.series("kinetic_energy") + sim.series("potential_energy")
    wave = 0.25 * 1000.0 * 9.81 * 0.008**2 * 0.4  # J/m, the first mode's energy
    return e, wave


@pytest.mark.slow
def test_standing_wave_does_not_gain_energy():
    """Sloshing at 0.01 m for 3 s (4 periods): the energy stays within a tenth of the wave's
    own energy of its initial value (the issue's bound, 0.5% of the initial energy, is 6
    wave energies); the earlier default, whose density correction the particles kept as
    velocity, gained more than a whole wave's energy in the same time, so the check can
    fail."""
    e, wave = _sloshing_energy([])
    assert np.max(e - e[0]) < 0.1 * wave
    assert np.max(e - e[0]) < 0.005 * e[0]
    e_old, _ = _sloshing_energy(EARLIER)
    assert np.max(e_old - e_old[0]) > 1.0 * wave


@pytest.mark.slow
def test_consistent_surface_quadrature_only_takes_energy_out():
    """With divergence and gradient integrated alike over the material in surface cells the
    projection step is energy-stable: what remains is the time integration's own oscillation
    of the energy within a period (measured: 0.9% of the wave's energy), and the wave ends
    the 3 s with less energy than it started with."""
    e, wave = _sloshing_energy(["solver.surface_quadrature=consistent"])
    assert np.max(e - e[0]) < 0.02 * wave
    assert e[-1] < e[0]


def _energy_panel(series, summary, monkeypatch, tmp_path):
    """The energy panel of timeseries.png, as plot_timeseries drew it (save intercepted)."""
    from mpmflow.plotting import figures as plots
    from mpmflow.plotting.mpl import pyplot

    figures = []
    monkeypatch.setattr(plots, "save", lambda fig, path, dpi: figures.append(fig))
    plots.plot_timeseries(series, summary, tmp_path / "timeseries.png", pyplot())
    ax = figures[0].axes[1]
    return ax, {line.get_label(): line.get_ydata() for line in ax.get_lines()}


def test_total_energy_change_starts_at_zero_for_a_body_thrown_in(tmp_path, monkeypatch):
    """A block released at 1 m/s: "total - initial" is 0 at t = 0 (it started at the initial
    kinetic energy: only the initial potential energy was subtracted), and it is the change
    of kinetic plus potential energy after; the axis states J/m (2D)."""
    from mpmflow import open_run

    case = load_case(
        EXAMPLES / "hydrostatic.toml",
        [
            "output.snapshots=false",
            "time.end=0.03",
            "bodies.0.max=[0.05,0.1]",
            "bodies.0.velocity=[1.0,0.0]",
            "bodies.0.particles_per_cell=2",
        ],
    )
    Simulation(case, tmp_path / "run").run()
    run = open_run(tmp_path / "run")
    ke, pe = run.timeseries["kinetic_energy"], run.timeseries["potential_energy"]
    assert ke[0] == pytest.approx(0.5 * 1000.0 * 0.05 * 0.1 * 1.0**2)  # J/m
    ax, lines = _energy_panel(run.timeseries, run.summary, monkeypatch, tmp_path)
    assert lines["total - initial"][0] == 0.0
    assert np.array_equal(lines["total - initial"], ke + pe - (ke[0] + pe[0]))
    assert np.array_equal(lines["potential - initial"], pe - pe[0])
    assert ax.get_ylabel() == "energy [J/m]"


@pytest.mark.slow
def test_energy_axis_states_its_unit_in_3d_and_while_the_run_goes(tmp_path, monkeypatch):
    """3D energies are in J (the summary's units); a run still going has no summary, and the
    label says both units rather than guess J/m."""
    series = {
        c: np.array([0.0, 0.01])
        for c in (
            "time",
            "front",
            "height",
            "max_speed",
            "max_pressure",
            "pressure_noise",
            "volume_ratio",
        )
    }
    series.update(kinetic_energy=np.array([0.26, 0.5]), potential_energy=np.array([3.0, 2.8]))
    ax, lines = _energy_panel(series, {"units": {"kinetic_energy": "J"}}, monkeypatch, tmp_path)
    assert ax.get_ylabel() == "energy [J]"
    assert lines["total - initial"].tolist() == [0.0, (0.5 + 2.8) - (0.26 + 3.0)]
    ax, _ = _energy_panel(series, {}, monkeypatch, tmp_path)
    assert ax.get_ylabel() == "energy [J/m in 2D, J in 3D]"
