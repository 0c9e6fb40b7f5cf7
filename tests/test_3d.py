"""3D: the same core as 2D, with z up. Coarse meshes, so that CI stays short."""

import numpy as np
import pytest

from mpmflow import Simulation, load_case
from mpmflow.bodies import fills_grid, overlap_message
from mpmflow.diagnostics import front_and_height
from mpmflow.errors import CaseError
from mpmflow.grid import Grid

from conftest import EXAMPLES, make_case

RHO, G = 1000.0, 9.81


@pytest.mark.parametrize("depth, end", [(0.195, 1.0), (0.2, 0.2)])
def test_column_at_rest_in_3d_is_exact(depth, end):
    """The 3D column at rest with the defaults, surface half a cell off the grid (over 1 s)
    and on a grid line: the particle pressure is rho g (H - z) to 1e-6 relative and no
    particle moves faster than 1e-6 m/s, as in 2D."""
    case = load_case(EXAMPLES / "hydrostatic_3d.toml",
                     [f"bodies.0.max=[0.1, 0.05, {depth}]", f"time.end={end}",
                      "output.snapshots=false"])
    sim = Simulation(case)
    sim.run()
    assert sim.time == pytest.approx(end)
    P = sim.particles
    assert P.x.shape[1] == 3 and P.count == 10 * 5 * round(depth / 0.005) * 4
    assert np.nanmax(sim.series("max_speed")) <= 1e-6
    exact = RHO * G * (depth - P.x[:, 2])
    assert np.max(np.abs(P.pressure - exact)) <= 1e-6 * exact.max()


def test_every_vector_has_one_entry_per_axis():
    with pytest.raises(CaseError, match=r"bodies.0.max = \[0.1, 0.2\] has 2 entries but "
                                        r"domain.size = \[0.1, 0.05, 0.3\] has 3"):
        load_case(EXAMPLES / "hydrostatic_3d.toml", ["bodies.0.max=[0.1, 0.2]"])
    with pytest.raises(CaseError, match="physics.gravity"):
        load_case(EXAMPLES / "hydrostatic_3d.toml", ["physics.gravity=[0, -9.81]"])
    # defaults follow the dimension: gravity down the last axis, bodies at rest
    case = make_case(size=(0.1, 0.05, 0.3), body=((0, 0, 0), (0.1, 0.05, 0.2)), ppc=2)
    assert case.physics.gravity == [0.0, 0.0, -9.81] and case.bodies[0].velocity == [0.0] * 3
    assert make_case().physics.gravity == [0.0, -9.81]


@pytest.mark.parametrize("override, words", [
    (["bodies.0.surface_amplitude=0.01"], "cosine top surface is defined for 2D cases only"),
])
def test_what_is_2d_only_is_refused_in_3d_with_the_fix(override, words):
    with pytest.raises(CaseError, match=words):
        load_case(EXAMPLES / "hydrostatic_3d.toml", override)


def test_overlapping_and_filling_bodies_in_3d():
    case = make_case(size=(0.1, 0.05, 0.3), body=((0, 0, 0), (0.1, 0.05, 0.2)), ppc=2)
    a = case.bodies[0]
    b = a.model_copy(update={"min": [0.05, 0.0, 0.1], "max": [0.1, 0.05, 0.3]})
    message = overlap_message([a, b], 0.01)
    assert message and "x = 0.05 to 0.1 m, y = 0 to 0.05 m, z = 0.1 to 0.2 m" in message
    apart = b.model_copy(update={"min": [0.0, 0.0, 0.2]})  # touches a's top face only
    assert overlap_message([a, apart], 0.01) is None
    assert not fills_grid([a], 0.01, [0.1, 0.05, 0.3])
    assert fills_grid([a, apart], 0.01, [0.1, 0.05, 0.3])
    with pytest.raises(CaseError, match="fill the whole domain"):
        make_case(size=(0.1, 0.05, 0.2), body=((0, 0, 0), (0.1, 0.05, 0.2)), ppc=2)


def test_front_and_height_of_an_extruded_field_are_the_2d_ones():
    rng = np.random.default_rng(3)
    g2, g3 = Grid(0.01, (12, 9)), Grid(0.01, (12, 4, 9))
    theta2 = rng.uniform(0, 1.3, (9, 12))  # [cy, cx]
    theta3 = np.repeat(theta2[:, None, :], 4, axis=1)  # [cz, cy, cx]: the same in every slice
    f2, h2 = front_and_height(g2, theta2.ravel())
    f3, h3 = front_and_height(g3, theta3.ravel())
    assert f3 == pytest.approx(f2, abs=1e-15) and h3 == pytest.approx(h2, abs=1e-15)


def test_3d_outputs_read_back_and_plot(tmp_path):
    """Snapshots keep z, energies are in J (not J/m), and `mpmflow plot` draws the x-z slice
    through the middle of the width."""
    pytest.importorskip("matplotlib")
    from mpmflow import open_run
    from mpmflow.plots import plot_run, side_view

    case = load_case(EXAMPLES / "hydrostatic_3d.toml", ["time.end=0.02"])
    sim = Simulation(case, tmp_path / "o")
    sim.run()
    run = open_run(tmp_path / "o")
    assert run.units["kinetic_energy"] == "J" and run.units["potential_energy"] == "J"
    snap = run.snapshots[-1].read()
    np.testing.assert_allclose(snap["x"], sim.particles.x, rtol=1e-6)
    xz, p, plane, names, caption = side_view(snap["x"], snap["pressure"], [0.1, 0.05, 0.3], 0.01)
    assert names == ("x", "z") and plane == [0.1, 0.3] and "y = 0.025" in caption
    in_slice = np.abs(snap["x"][:, 1] - 0.025) <= 0.005
    assert 0 < len(xz) == in_slice.sum() < len(snap["x"])  # a slice, not everything
    np.testing.assert_array_equal(xz, snap["x"][in_slice][:, [0, 2]])
    figures = plot_run(tmp_path / "o", tmp_path / "plots")
    assert any(f.name == "snapshots.png" for f in figures)
