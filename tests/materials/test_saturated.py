"""A saturated soil (material.model = "poroelastic"): Terzaghi's consolidation, a step that
no permeability limits, and the pore water at rest when the skeleton has taken its weight."""

import numpy as np
import pytest
from conftest import EXAMPLES

from mpmflow import Simulation, load_case
from mpmflow.errors import CaseError
from mpmflow.materials import poroelastic
from mpmflow.parallel.support import refusals
from mpmflow.validation import saturated


def test_the_pore_pressure_dissipates_at_terzaghis_rate():
    """The column at H / 10 (steps of 0.002 in T_v): its degree of consolidation within the
    issue's 2% of Terzaghi's series over 0.01 <= T_v <= 2, its isochrones within 3% of the
    load (measured: 0.0117 and 0.017; the validation report's finest mesh: 0.0012, 0.0022)."""
    r = saturated.consolidation(0.1, 1e-5, 0.002, EXAMPLES)
    assert r["sim"].steps == 1000
    assert saturated.u_error(r) <= 0.02
    assert set(r["iso"]) == set(saturated.ISOCHRONES)
    assert max(r["iso"].values()) <= 0.03


def test_the_step_does_not_depend_on_the_permeability():
    """k = 1e-3 and 1e-9 m/s at the same step in T_v (dt 2 ms and 2000 s): the same steps,
    both within 2% of Terzaghi; an explicit two-phase step would be 1e6 times shorter for
    the second (saturated.explicit_step)."""
    errors = []
    for k in (1e-3, 1e-9):
        r = saturated.consolidation(0.1, k, 0.002, EXAMPLES)
        assert r["sim"].steps == 1000
        errors.append(saturated.u_error(r))
    assert max(errors) <= 0.02
    assert saturated.explicit_step(1e-9, 0.1) < 1e-9


@pytest.mark.parametrize("h, tol", [(0.1, 0.05)])
def test_a_column_consolidated_under_its_weight_rests_on_its_skeleton(h, tol):
    """Gravity on, no load, the skeleton unstressed at the start: the column consolidates
    under its buoyant weight and ends (T_v = 3) with the pore water hydrostatic, p = rho_w g
    (H - y), to 1e-3 rho_w g H (Terzaghi's excess left at T_v = 3 is 6e-4 of it), the
    effective stress carrying the buoyant weight, sigma'_yy = -(rho - rho_w) g (H - y),
    within h / (2 H) of (rho - rho_w) g H (half a cell of weight: the particles' stress
    sampled from the grid's velocity gradients; measured 0.026 at H / 10, 0.013 at H / 20:
    first order), sigma'_xx / sigma'_yy = nu / (1 - nu) (the confined elastic column's K0)
    to 1e-9, and the particles at rest."""
    sets = ["physics.gravity=[0.0, -9.81]", f"grid.spacing={h}", "loads=[]"]
    case = load_case(EXAMPLES / "terzaghi.toml", sets)
    m = case.material
    cv = poroelastic.consolidation_coefficient(m)
    dt = 0.002 / cv
    sets += [f"time.dt={dt!r}", f"time.end={3 / cv!r}", f"output.interval={100 * dt!r}"]
    sim = Simulation(load_case(EXAMPLES / "terzaghi.toml", sets))
    depth = 1.0 - sim.particles.x[:, 1].copy()
    sim.run()
    g, rho_w = 9.81, m.water_density
    p = sim.particles.pressure
    assert np.max(np.abs(p - rho_w * g * depth)) <= 1e-3 * rho_w * g
    s = sim.history["stress"]
    buoyant = (m.density - rho_w) * g
    assert np.max(np.abs(s[:, 1, 1] + buoyant * depth)) <= tol * buoyant
    k0 = m.poisson_ratio / (1 - m.poisson_ratio)
    assert s[:, 0, 0] == pytest.approx(k0 * s[:, 1, 1], rel=1e-9, abs=1e-9 * buoyant)
    assert np.abs(sim.particles.v).max() < 1e-6


def test_bad_saturated_soils_are_refused():
    def case(*sets):
        return load_case(EXAMPLES / "terzaghi.toml", list(sets))

    with pytest.raises(CaseError, match="poisson_ratio"):
        case("material.poisson_ratio=0.5")
    with pytest.raises(CaseError, match="permeability"):
        case("material.permeability=0.0")
    with pytest.raises(CaseError, match="water_density"):
        case("material.water_density=2500.0")
    with pytest.raises(CaseError, match="parameter of material.model"):
        case('material.model="elastic"')
    assert any("saturated soil" in p for p in refusals(case("loads=[]")))


def test_still_water_over_a_saturated_bed_stays_at_rest():
    """examples/seabed.toml over 2 s (200 steps): free water over a bed whose skeleton
    starts with its buoyant weight; the pore pressure stays hydrostatic from the water's
    surface through the bed to the issue's 1e-6 rho_w g H, every particle slower than
    1e-6 m/s (measured 4e-13 and 2e-13 over the example's 20 s)."""
    r = saturated.still_bed(["time.end=2.0"], EXAMPLES)
    assert r["sim"].steps == 200
    assert r["pressure"] <= 1e-6
    assert r["speed"] <= 1e-6


def test_free_water_and_a_geostatic_start_are_checked():
    with pytest.raises(CaseError, match="free_water = true is the free water beside"):
        load_case(EXAMPLES / "cantilever.toml", ["bodies.0.free_water=true"])
    with pytest.raises(CaseError, match="needs physics.gravity down the last axis"):
        load_case(EXAMPLES / "seabed.toml", ["physics.gravity=[1.0, -9.81]"])
    case = load_case(EXAMPLES / "seabed.toml")
    sim = Simulation(case)
    water = poroelastic.free_water(case.material, sim.particles.mass, sim.particles.volume)
    assert water.sum() == sim.particles.count // 2  # the upper body, as many as the bed
    assert np.all(sim.particles.x[water, 1] > 0.4)


def test_a_saturated_soils_snapshots_and_checkpoints(tmp_path):
    """The snapshot names the stress "effective_stress" (its volumetric part included: the
    bed's geostatic sigma'_yy is -(rho - rho_w) g d), the pressure is the pore pressure; a
    run resumed from a checkpoint keeps the skeleton's stress (not the geostatic start again)
    and ends where an uninterrupted run ends, bit for bit (Terzaghi's column, loaded)."""
    import shutil

    import meshio

    sets = ["time.end=20.0", "output.snapshots=true", "output.snapshot_interval=20.0"]
    sets += ["checkpoint.interval=8.0", "physics.gravity=[0.0, -9.81]"]
    sets += ['material.initial_stress="geostatic"']
    whole = Simulation(load_case(EXAMPLES / "terzaghi.toml", sets), out_dir=tmp_path / "whole")
    whole.run()
    mesh = meshio.read(sorted((tmp_path / "whole").glob("particles_*.vtu"))[-1])
    stress = mesh.point_data["effective_stress"].reshape(-1, 3, 3)
    assert np.array_equal(stress[:, :2, :2], whole.history["stress"])
    assert stress[:, 1, 1].min() < -0.9 * (2000.0 - 1000.0) * 9.81 * 1.0  # the base's weight
    out = tmp_path / "parts"
    shutil.copytree(tmp_path / "whole", out)
    checkpoint = sorted(out.glob("checkpoint_*.npz"))[0]
    rest = Simulation.resume(load_case(EXAMPLES / "terzaghi.toml", sets), out, checkpoint)
    rest.run()
    assert np.array_equal(rest.history["stress"], whole.history["stress"])
    assert np.array_equal(rest.particles.x, whole.particles.x)
    assert np.array_equal(rest.particles.pressure, whole.particles.pressure)


def test_the_darcy_flux_at_the_particles_is_terzaghis():
    """The pore water's flux relative to the skeleton, in the snapshots as darcy_flux:
    k / (rho_w g_n) times the pore pressure's gradient, against the series' q_y = (k /
    (rho_w g_n)) (q / H) sum 2 cos(M Z) exp(-M^2 T_v) at T_v = 0.2 (H / 40): within 3% of
    its largest value (measured 2.4%: the nodal pressure's gradient at the particles),
    and no horizontal flux beyond 2% of it (measured 0.9%)."""
    h = 0.025
    case = load_case(EXAMPLES / "terzaghi.toml", [f"grid.spacing={h}"])
    cv = poroelastic.consolidation_coefficient(case.material)
    dt = 0.001 / cv
    sets = [f"grid.spacing={h}", f"time.dt={dt!r}", f"time.end={0.2 / cv!r}"]
    sim = Simulation(
        load_case(EXAMPLES / "terzaghi.toml", [*sets, f"output.interval={0.2 / cv!r}"])
    )
    z = 1.0 - sim.particles.x[:, 1].copy()
    sim.run()
    q = sim.scheme.darcy_flux()  # (the column is weightless)
    M = np.pi * (2 * np.arange(200) + 1) / 2
    tv = sim.time * cv
    series = np.sum(2 * np.cos(np.outer(z, M)) * np.exp(-(M**2) * tv), axis=1)
    expected = poroelastic.mobility(case.material) * 1e4 * series
    assert np.max(np.abs(q[:, 1] - expected)) <= 0.03 * expected.max()
    assert np.max(np.abs(q[:, 0])) <= 0.02 * expected.max()


def test_terzaghis_column_in_3d():
    """The column in 3D (0.2 x 0.2 m, H / 10, the load on its top face): the same 2% and
    3% as in 2D (measured 0.0117 and 0.018, as the 2D column's 0.0117 and 0.017): the pore
    flow's faces and the skeleton's bulk stiffness are the 3D kernels'."""
    sets = [
        "domain.size=[0.2, 0.2, 1.2]",
        "bodies.0.min=[0.0, 0.0, 0.0]",
        "bodies.0.max=[0.2, 0.2, 1.0]",
        'loads=[{axis="z", at=1.0, lower=[0.0, 0.0], upper=[0.2, 0.2], traction=[0.0, 0.0, -1e4]}]',
        "physics.gravity=[0.0, 0.0, 0.0]",
    ]
    r = saturated.consolidation(0.1, 1e-5, 0.002, EXAMPLES, sets)
    assert r["sim"].steps == 1000
    assert saturated.u_error(r) <= 0.02
    assert set(r["iso"]) == set(saturated.ISOCHRONES)
    assert 0.0 < max(r["iso"].values()) <= 0.03


def test_mandels_slab_under_a_rigid_plate():
    """Mandel's problem at h = a / 10 (examples/mandel.toml, 400 steps): the centre's pore
    pressure within the issue's 5% of p0 of Mandel's solution over 0.01 <= T <= 1 (measured
    0.0055), and its Mandel-Cryer rise above p0 within a tenth of Mandel's (measured 0.1033
    against 0.1066): the plate's one velocity meets its force each step."""
    r = saturated.mandel(0.1, EXAMPLES)
    assert r["sim"].steps == 400
    sel = r["tv"] >= 0.01
    assert np.max(np.abs(r["p"][sel] - r["ref"][sel])) <= 0.05
    rise, ref_rise = r["p"].max() - 1, r["ref"].max() - 1
    assert ref_rise > 0.1 and abs(rise / ref_rise - 1) <= 0.1


def test_a_plate_is_checked():
    with pytest.raises(CaseError, match="a rigid plate presses a saturated soil"):
        load_case(EXAMPLES / "cantilever.toml", ['plate.side="y_max"', "plate.force=-1.0"])
    with pytest.raises(CaseError, match="not a side of a 2D domain"):
        load_case(EXAMPLES / "mandel.toml", ['plate.side="z_max"'])
    assert any("plate" in p for p in refusals(load_case(EXAMPLES / "mandel.toml")))


def test_a_plate_continues_from_a_checkpoint(tmp_path):
    """The plate's velocity is in the checkpoint (the next step's first guess): a resumed
    run ends where an uninterrupted one ends, bit for bit."""
    import shutil

    sets = ["grid.spacing=0.1", "time.end=10.0", "output.interval=2.5"]
    sets += ["checkpoint.interval=5.0"]
    whole = Simulation(load_case(EXAMPLES / "mandel.toml", sets), out_dir=tmp_path / "whole")
    whole.run()
    out = tmp_path / "parts"
    shutil.copytree(tmp_path / "whole", out)
    checkpoint = sorted(out.glob("checkpoint_*.npz"))[0]
    rest = Simulation.resume(load_case(EXAMPLES / "mandel.toml", sets), out, checkpoint)
    rest.run()
    assert np.array_equal(rest.particles.pressure, whole.particles.pressure)
    assert np.array_equal(rest.particles.x, whole.particles.x)
    assert rest.scheme.state()["plate_velocity"] == whole.scheme.state()["plate_velocity"] < 0
