"""Solids with a stress history on the particles (material.model = "elastic", "von_mises",
"drucker_prager"; src/core/plasticity.hpp, src/core/solid.hpp; docs/method.md, "Solids").

Physics: a column at rest stays at rest with the hydrostatic pressure; the stress step is
objective (a rigid spin turns the stress without changing its invariant) and returns to the
yield surface exactly; an elastic layer on a slope oscillates at the shear-wave period 4 H /
c_s, converging as the mesh is refined; a clay layer stands where its strength exceeds the
shear the slope puts on it and flows where it does not, converging at first order; a
cantilever swings about and comes to rest at its static deflection, at the solid's step and
past it (the coupled step). Input: schemes and runs that do not carry the stress refuse
solids by name, and a step past a solid's that the coupled step does not take is refused.
"""

import math

import numpy as np
import pytest
from conftest import ROOT

from mpmflow import Simulation, load_case, state
from mpmflow.errors import CaseError
from mpmflow.parallel.support import refusals

HYDRO = "examples/hydrostatic.toml"
SOLIDS = [
    ["material.model='elastic'"],
    ["material.model='von_mises'", "material.undrained_strength=100.0"],
    ["material.model='drucker_prager'", "material.friction_angle=30.0"],
]


@pytest.mark.parametrize(
    "extra",
    [*SOLIDS, [*SOLIDS[0], "solver.transfer='apic'"]],
    ids=["elastic", "von_mises", "drucker_prager", "elastic_apic"],
)
def test_a_solid_column_at_rest_stays_at_rest(extra):
    """Between slip walls the column's deviatoric stress stays 0 and its pressure is the
    projection's (the issue's bound is 1e-6 m/s and 1e-6 rho g H); with APIC transfers too
    (the stress update maps APIC's velocities back). A solid's pressure lives on the cells
    (src/core/cell_pressure.hpp) and its surface is natural, so the column's top, half a
    cell above a row of nodes, needs no ghost value: its cells' pressures are the
    hydrostatic one at their material's centroid and the particles read it through the
    cells' linear reconstruction. What is left is the solves' tolerance (solver.tolerance =
    1e-8, a relative residual): the pressure within 1e-8 of rho g H (measured 2.3e-9), the
    velocities it leaves (1e-10 m/s) integrated by the stress to under 1e-5 Pa, 5e-9 of
    rho g H (measured 1.4e-6 Pa with APIC, 7e-7 without). The water's node pressure meets the same column to 1e-12."""
    case = load_case(
        ROOT / HYDRO,
        ["time.end=0.2", "output.snapshots=false", "material.shear_modulus=1e4", *extra],
    )
    sim = Simulation(case)
    sim.run()
    P = sim.particles
    exact = case.material.density * 9.81 * (0.195 - P.x[:, 1])
    assert np.abs(P.v).max() < 1e-9
    assert np.abs(P.pressure - exact).max() < 1e-8 * exact.max()
    assert np.abs(sim.history["stress"]).max() < 1e-5  # Pa, against 1.9 kPa


def test_a_free_standing_elastic_block_settles_and_bulges():
    """An incompressible elastic block (0.2 x 0.1 m, G = 1 MPa) on a bonded floor, its
    sides and top free, comes to rest under gravity (damped by PIC transfers) with its top
    settled and its sides bulged out: its volume is kept, so what the top loses the sides gain. The settlement is
    bounded above by that of the same block on a frictionless floor, a column in uniaxial
    stress (rho g H^2 / (2 E), E = 3 G), which the bonded floor can only stiffen. With the
    fluid's free surface (p = 0 at the surface nodes) the top rose and the sides moved in."""
    case = load_case(
        ROOT / "tests/materials/block.toml", ["output.snapshots=false", "time.end=0.6"]
    )
    sim = Simulation(case)
    x0 = sim.particles.x.copy()
    top = int(np.argmin(np.abs(x0[:, 0] - 0.3) + np.abs(x0[:, 1] - x0[:, 1].max())))
    side = int(np.argmin(np.abs(x0[:, 0] - x0[:, 0].max()) + np.abs(x0[:, 1] - 0.05)))
    sim.run()
    P = sim.particles
    sag = x0[top, 1] - P.x[top, 1]
    bulge = P.x[side, 0] - x0[side, 0]
    uniaxial = 1000.0 * 9.81 * 0.1**2 / (2 * 3 * 1e6)
    assert np.abs(P.v).max() < 1e-6  # m/s: at rest
    assert 0.2 * uniaxial < sag < uniaxial  # measured 6.7e-6 m, 0.41 of it
    assert bulge > 0.0  # measured 9.5e-6 m


def test_a_rigid_plate_carries_a_blocks_weight():
    """A solid's tool (an obstacle on a path) holds the grid's nodes inside it, and the
    material's force on it is those nodes' reactions (pressure, shear and the inertia of
    what it carries): an elastic block at rest on a plate presses on it with its weight,
    rho g V = 4,905 N/m, to the solves' tolerance (measured 1e-8 of it), and stays at rest."""
    sim = Simulation(load_case(ROOT / "tests/materials/plate.toml"))
    sim.run()
    force = sim.scheme.core.body_force[0]
    weight = 1000.0 * 9.81 * 1.0 * 0.5
    assert abs(force[1] + weight) < 1e-6 * weight
    assert abs(force[0]) < 1e-6 * weight
    assert np.abs(sim.particles.v).max() < 1e-6  # m/s


def test_past_its_step_a_solid_takes_the_coupled_step_with_a_tool():
    """The plate of the test above at time.dt = 10 ms, ten times the solid's step (0.5 h /
    c_s = 0.99 ms): the coupled step holds the tool's nodes as the split step's contacts
    do, and the plate carries the block's weight to the solves' tolerance (measured 1e-8)."""
    case = load_case(ROOT / "tests/materials/plate.toml", ["time.dt=0.01", "time.end=0.5"])
    sim = Simulation(case)
    sim.run()
    force = sim.scheme.core.body_force[0]
    weight = 1000.0 * 9.81 * 1.0 * 0.5
    assert abs(force[1] + weight) < 1e-6 * weight
    assert np.abs(sim.particles.v).max() < 1e-6  # m/s


def _slide(h, dt, dim=2):
    """The clay layer of ``_layer`` (s_u = 100 Pa: its base yields and it slides) at a fixed
    step dt (s): the top row's mean downslope acceleration (m/s^2) from 0.2 to 0.3 s, and
    the run's plastic iterations (State::plastic_solve; 0 at the split step)."""
    sim = Simulation(_layer_case(h, "von_mises", 0.3, 100.0, dim, dt, interval=0.01))
    top = sim.particles.x[:, dim - 1] > 0.05 - h
    r = sim.scheme.advance(dt, round(0.2 / dt))
    u0 = sim.particles.v[top, 0].mean()
    r = r.merge(sim.scheme.advance(dt, round(0.1 / dt)))
    return (sim.particles.v[top, 0].mean() - u0) / 0.1, r.plastic_iterations


def test_the_coupled_step_returns_plastic_flow_within_the_solve():
    """Past the solid's step the coupled step iterates on each particle's return factor
    (State::plastic_solve) until the stress the solve takes is the radial return of the
    velocity it gives. Before, the return acted on the whole long increment after a solve
    that held no plastic tangent, and a footing on Tresca clay bore 2 s_u at 2.5 times the
    step against 5 s_u at it, so plastic flow there was refused. The sliding clay layer of
    the test above at h = 5 mm (the solid's step 0.35 ms) at 2 and 5 ms, 6 and 14 times
    it, and in 3D (a periodic column 4 x 4 cells across) at 2 ms: its acceleration within
    1% of the lumped-mass value, as at the solid's step (measured +0.37% and +0.41%, 3D
    +0.37%, against +0.34% at 0.2 ms in 2D and 3D), with the plastic iterations taken
    (at most 18 a step at 5 ms)."""
    g, H, su, rho, h = 9.81 * math.sin(math.radians(20.0)), 0.05, 100.0, 2000.0, 0.005
    lumped = g * (1 - h / (2 * H)) - su / (rho * H)
    for dt, dim in ((2e-3, 2), (5e-3, 2), (2e-3, 3)):
        acceleration, iterations = _slide(h, dt, dim)
        assert acceleration == pytest.approx(lumped, rel=0.01), (dt, dim, acceleration)
        assert iterations > 0, (dt, dim)


def test_a_frictional_soil_past_its_step_is_refused():
    """The plastic iterations settle a Tresca clay but stalled on the Drucker-Prager column
    of examples/bui_column.toml at 5 times the solid's step (a stress change of 2e-3 to
    1e-2 of the largest from 0.34 s on): past its step a frictional soil is refused, naming
    the step to take; at it, it runs split (time.dt = "auto")."""
    with pytest.raises(CaseError, match=r"above a solid's step.*pressure-dependent strength"):
        load_case(ROOT / "examples/bui_column.toml", ["time.dt=0.001"])
    load_case(ROOT / "examples/bui_column.toml", ["time.dt=9e-5"])


def test_a_footing_past_its_step_bears_the_load_of_the_solids_step():
    """The footing of examples/footing.toml at B / 16 (its edge on a plane of nodes, where
    the numbers below were measured) at 2.5 times the solid's step (1.1 ms; coupled, with
    the plastic iterations) to a settlement of 0.005 B: its load within 5% of the solid's
    step's (measured 4.746 s_u against 4.639, +2.3%; 5.540 against 5.384 at 0.01 B,
    +2.9%; over the plateau's 0.02-0.03 B, with the tools' reach of before 2026-11-30,
    5.765 against 5.559, +3.7%: the two steps return the plastic flow by different means,
    the split step leaving a yielded cell's stiffness out, and the difference does not
    shrink towards the solid's step: +3.4% at 1.13 times it). Before the plastic
    iterations, 2 s_u (a box of 2.5 x 1.5 B)."""
    loads = []
    for dt in ("'auto'", "1.1e-3"):
        case = load_case(
            ROOT / "examples/footing.toml",
            ["grid.spacing=0.0625", f"time.dt={dt}", "time.end=0.05"],
        )
        sim = Simulation(case)
        sim.run()
        loads.append(abs(sim.scheme.core.body_force[0][1]) / 0.5 / 1e4)  # q / s_u
    assert loads[0] > 4.5 and abs(loads[1] / loads[0] - 1) < 0.05, loads


def test_a_footings_force_is_the_clays_vertical_stress():
    """The footing of examples/footing.toml, 0.25 s in (a settlement of 0.025 B, on the
    load's plateau: the clay at its limit under it): its nodes' reactions against the
    clay's own vertical stress, integrated over a band 0.5-2.5 m above the base (the
    footing's face is at 3 m), which carries the whole load of a weightless layer between
    frictionless side walls. The two are independent measures; they agree to the inertia
    of the slowly moving clay (measured 0.37%; 0.42% at B / 16, 0.25% there at G = 100
    s_u). With the cut cells' pressure integral that fluids' bodies take (the shear left
    out) and their cut-cell contact, the footing blew up within 0.05 s. And the load is
    Prandtl's within 5% at this mesh (B / 15, the footing's edge midway between two nodes:
    measured +3.2%), where a tool that held the nodes within a cell beside its faces as well
    as ahead of them bore 1.156 of it (src/core/bodies.hpp, REACH)."""
    sim = Simulation(
        load_case(ROOT / "examples/footing.toml", ["time.end=0.25", "output.snapshots=false"])
    )
    sim.run()
    P = sim.particles
    syy = sim.history["stress"][:, 1, 1] - P.pressure
    band = (P.x[:, 1] > 0.5) & (P.x[:, 1] < 2.5)
    carried = -np.sum(P.volume[band] * syy[band]) / 2.0  # N/m
    force = float(sim.scheme.core.body_force[0, 1])
    assert abs(force / (0.5 * 1e4 * (2.0 + np.pi)) - 1) < 0.05  # q against (2 + pi) s_u
    assert abs(force / carried - 1) < 0.03


def _cantilever(sets):
    """The cantilever of examples/cantilever.toml at h = H / 4 under ``sets``: the tip's
    deflection (the particle nearest the end of the neutral axis) over Timoshenko's static
    one at each output from t = 0, and the run."""
    from mpmflow.validation import solids

    case = load_case(
        ROOT / "examples/cantilever.toml", ["output.snapshots=false", "grid.spacing=0.025", *sets]
    )
    sim = Simulation(case)
    x0 = sim.particles.x.copy()
    k = int(np.argmin(np.abs(x0[:, 0] - x0[:, 0].max()) + np.abs(x0[:, 1] - 0.3)))
    tips: list[float] = []
    sim.on_output = lambda s: tips.append((x0[k, 1] - s.particles.x[k, 1]) / solids.DELTA)
    sim.run()
    return np.array(tips), sim


def test_a_cantilever_swings_about_its_static_deflection():
    """Released suddenly, the beam swings between 0 and twice the static deflection with the
    period of its first mode, T = 0.161 s: over the first period its tip's mean is the
    static deflection (the validation row's measure, docs/validation), within the issue's 3%
    (measured +2.1%; 0.874 of it before the projection took the nodes' mass and the stress's
    force stopped passing through the particles), and its deepest point comes at half the
    period within 5% (measured 2.03 times the deflection at 0.512 T; 1.98 at 0.44 T before,
    and 1.44 at 0.375 T at h = H / 8)."""
    from mpmflow.validation import solids

    n = 80
    tips, _ = _cantilever(
        [f"time.end={solids.PERIOD:.6f}", f"output.interval={solids.PERIOD / n:.6f}"]
    )
    assert abs(tips[:n].mean() - 1) < 0.03, tips[:n].mean()
    assert abs(np.argmax(tips) / n - 0.5) < 0.05, np.argmax(tips) / n


def test_a_damped_cantilever_comes_to_rest_at_its_static_deflection():
    """Damped by PIC transfers at the solid's step, the beam comes to rest where its spatial
    discretisation puts it: Q1 velocities, the particles' quadrature and one
    incompressibility constraint per cell, solved statically (scripts/solid_statics.py),
    give 1.012 times Timoshenko's deflection at h = H / 4. From 0.64 s (four periods) to 0.8 s
    the tip stays within 1% of that (measured 1.004 to 1.013) and so within the issue's 3% of
    the theory, and the particles are slower than 2 mm/s (0.77 mm/s; 0.3 m/s in the first
    swing). With the particles' velocities mapped back to the grid for the stress (modified
    update-stress-last) it came to rest 34% too deep: the stress fell behind the strain."""
    tips, sim = _cantilever(["solver.flip=0.0", "time.end=0.8", "output.interval=0.02"])
    late = tips[32:]  # t = 0.64 to 0.8 s
    assert np.abs(late - 1.012).max() < 0.01, late
    assert np.abs(sim.particles.v).max() < 2e-3  # m/s


PAR = np.array([1e6, 0.0, 0.0, 0.0])  # G = 1 MPa


def test_an_elastic_step_in_simple_shear_adds_g_gamma():
    s = np.zeros((2, 2))
    L = np.array([[0.0, 2.0], [0.0, 0.0]])  # du/dy = 2 /s
    plastic = state.update_stress(state.ELASTIC, PAR, L, 1e-3, 0.0, 0.0, s)
    # s_xy = 2 G D_xy dt = G (du/dy) dt; the spin of the first step acts on s = 0
    assert s[0, 1] == pytest.approx(1e6 * 2.0 * 1e-3, rel=1e-15)
    assert s[1, 0] == s[0, 1] and s[0, 0] == 0.0 and s[1, 1] == 0.0 and plastic == 0.0


@pytest.mark.parametrize("D", [2, 3])
def test_a_rigid_spin_turns_the_stress_and_keeps_its_invariant(D):
    """The Jaumann rate: under a rigid rotation at omega the stress turns with the body;
    forward steps turn its deviator at 2 omega, so J2 grows by (2 omega dt)^2 = 4e-8 a step:
    4e-5 over 1000 steps."""
    s = np.zeros((D, D))
    s[0, 0], s[1, 1] = 100.0, -100.0
    L = np.zeros((D, D))
    L[0, 1], L[1, 0] = -1.0, 1.0  # rotation about the last axis at 1 rad/s
    j2 = 0.5 * np.sum(s * s)
    for _ in range(1000):
        state.update_stress(state.ELASTIC, PAR, L, 1e-4, 0.0, 0.0, s)
    assert 0.5 * np.sum(s * s) == pytest.approx(j2 * (1 + 4e-8) ** 1000, rel=1e-9)
    # turned by 0.1 rad: s_xy = 100 sin(0.2) (a symmetric tensor turns at twice the angle)
    assert s[0, 1] == pytest.approx(100.0 * math.sin(0.2), rel=1e-3)
    assert abs(np.trace(s)) < 1e-12


@pytest.mark.parametrize("D", [2, 3])
def test_von_mises_returns_to_the_undrained_strength(D):
    par = np.array([1e6, 20e3, 1e3, 2.0])  # s_u = 20 kPa at y = 2 m, + 1 kPa/m below
    s = np.zeros((D, D))
    L = np.zeros((D, D))
    L[0, 1] = 100.0  # a shear far beyond the elastic range
    plastic = state.update_stress(state.VON_MISES, par, L, 1e-3, 0.0, 1.0, s)
    k = 20e3 + 1e3 * 1.0  # 1 m below the datum
    assert math.sqrt(0.5 * np.sum(s * s)) == pytest.approx(k, rel=1e-14)
    trial = 1e6 * 100.0 * 1e-3  # sqrt(J2) of the elastic trial: G gamma
    assert plastic == pytest.approx((trial - k) / (math.sqrt(3.0) * 1e6), rel=1e-14)


@pytest.mark.parametrize("D", [2, 3])
def test_drucker_prager_reads_the_pressure_and_parts_in_tension(D):
    phi = math.radians(30.0)
    c = 1e3
    par = np.array([1e6, math.sin(phi), c * math.cos(phi), 500.0])
    L = np.zeros((D, D))
    L[0, 1] = 100.0
    for p in (0.0, 1e4, -400.0):
        s = np.zeros((D, D))
        state.update_stress(state.DRUCKER_PRAGER, par, L, 1e-3, p, 0.0, s)
        k = p * math.sin(phi) + c * math.cos(phi)
        assert math.sqrt(0.5 * np.sum(s * s)) == pytest.approx(k, rel=1e-14), p
    s = np.zeros((D, D))
    plastic = state.update_stress(state.DRUCKER_PRAGER, par, L, 1e-3, -600.0, 0.0, s)
    assert np.all(s == 0.0) and plastic > 0.0  # below the cut-off: parted


def _layer_case(h, model, end, strength=None, dim=2, dt="auto", interval=0.001):
    """An elastic (or clay) layer H = 0.05 m deep, bonded to the floor of a periodic strip
    8 cells wide and 0.1 m tall (in 3D a periodic column of 4 x 4 cells, 0.06 m tall),
    under gravity tilted by 20 degrees along x (an infinite slope), G = 1e5 Pa, rho = 2000
    kg/m^3, steps of dt (s, or "auto"), to ``end`` (s), an output every ``interval`` (s):
    the case."""
    H, th = 0.05, math.radians(20.0)
    g = [9.81 * math.sin(th), -9.81 * math.cos(th)]
    if dim == 3:
        g = [g[0], 0.0, g[1]]
    across = [4 * h] if dim == 3 else []
    along, top = (4 * h, 0.06) if dim == 3 else (8 * h, 0.1)
    sets = [
        f"domain.size={[along, *across, top]}",
        f"domain.walls={{{'xyz'[dim - 1]}_min='bonded'}}",
        f"domain.periodic={str([True] * (dim - 1) + [False]).lower()}",
        f"grid.spacing={h}",
        f"bodies.0.min={[0.0] * dim}",
        f"bodies.0.max={[along, *across, H]}",
        "bodies.0.particles_per_cell=2",
        f"material.model='{model}'",
        "material.density=2000.0",
        "material.shear_modulus=1e5",
        f"physics.gravity={g}",
        f"time.dt={dt!r}",
        f"time.end={end}",
        f"output.interval={interval}",
        "output.snapshots=false",
    ]
    if strength is not None:
        sets.append(f"material.undrained_strength={strength}")
    example = HYDRO if dim == 2 else "examples/hydrostatic_3d.toml"
    return load_case(ROOT / example, sets)


def _layer(h, model, end, strength=None, dim=2):
    """The layer of ``_layer_case`` at time.dt = "auto": the simulation and the top's mean
    downslope velocity every 0.2 ms."""
    sim = Simulation(_layer_case(h, model, end, strength, dim))
    top = sim.particles.x[:, dim - 1] > 0.05 - h
    u = []
    for _ in range(round(end / 2e-4)):
        sim.scheme.advance(2e-4, 1)
        u.append(sim.particles.v[top, 0].mean())
    return sim, np.array(u)


def _period(u, dt=2e-4):
    """The mean period (s) between upward crossings of the signal's mean."""
    c = u - u.mean()
    k = np.flatnonzero((c[:-1] < 0) & (c[1:] >= 0))
    crossing = (k + 1 - c[k + 1] / (c[k + 1] - c[k])) * dt
    assert crossing.size >= 4
    return float(np.diff(crossing).mean())


def test_an_elastic_layer_rings_at_the_shear_wave_period():
    """The fundamental period of a layer fixed at its base and free at its top is 4 H / c_s
    (c_s = sqrt(G / rho) = 7.07 m/s: 28.3 ms). Measured (top's velocity, 0.15 s): +0.58% at
    H / 10, +0.10% at H / 20, +0.026% at H / 40, second order (+8.7%, +4.0%, +1.9% with the
    stress's force through the particles and the stress from their velocities); asserted:
    within 1% at H / 20, and at least 3 times closer than at H / 10."""
    exact = 4 * 0.05 / math.sqrt(1e5 / 2000.0)
    errors = [abs(_period(_layer(h, "elastic", 0.15)[1]) / exact - 1) for h in (0.005, 0.0025)]
    assert errors[1] < 0.01 and errors[0] > 3 * errors[1], errors


def test_an_elastic_layer_rings_at_the_shear_wave_period_in_3d():
    """The same layer in 3D (the kernels are written once for both; the 3D layer is the 2D
    one repeated across y): measured +0.10% at H / 20, the 2D number; asserted within 1%."""
    exact = 4 * 0.05 / math.sqrt(1e5 / 2000.0)
    error = abs(_period(_layer(0.0025, "elastic", 0.15, dim=3)[1]) / exact - 1)
    assert error < 0.01, error


def test_a_clay_layer_stands_or_flows_by_its_strength():
    """The slope puts a shear of rho g sin(20 deg) H = 335 Pa on the base, up to twice that
    while the suddenly loaded layer rings. At s_u = 2 kPa the layer stands: no particle
    yields and the top rings about rest (its mean velocity over the last 0.1 s, 3.5 periods,
    under 5 mm/s). At s_u = 100 Pa the base yields and the layer slides, held back by s_u:
    g sin(20 deg) - s_u / (rho H) = 2.355 m/s^2 for a block on a yield line of no
    thickness. On the grid the bonded floor's nodes hold the lowest half cell of material
    (its mass lumped there, h / (2 H) of the layer's), which gravity then cannot pull, so the
    layer accelerates at g sin(20 deg) (1 - h / (2 H)) - s_u / (rho H), first order in h:
    2.187 and 2.271 m/s^2 at h = 5 and 2.5 mm, measured (from 0.2 to 0.3 s) 2.195 and 2.282,
    -6.8% and -3.1% from the thin-line value. Asserted: within 1% of the lumped-mass value
    at both meshes, and the error against the thin line halving with h (first order). (The
    particles' force passed through the particles and back, before, leaked the floor
    nodes' share back into the layer: +0.8% at 5 mm.)"""
    sim, u = _layer(0.005, "von_mises", 0.3, strength=2000.0)
    assert sim.history["plastic_strain"].max() == 0.0
    assert abs(u[-500:].mean()) < 5e-3, u[-500:].mean()
    g, H, su, rho = 9.81 * math.sin(math.radians(20.0)), 0.05, 100.0, 2000.0
    errors = []
    for h in (0.005, 0.0025):
        sim, u = _layer(h, "von_mises", 0.3, strength=su)
        acceleration = (u[-1] - u[999]) / 0.1  # u every 0.2 ms: from 0.2 s to 0.3 s
        lumped = g * (1 - h / (2 * H)) - su / (rho * H)
        assert acceleration == pytest.approx(lumped, rel=0.01), (h, acceleration)
        assert sim.history["plastic_strain"].max() > 0.0
        errors.append(abs(acceleration / (g - su / (rho * H)) - 1))
    assert errors[0] / errors[1] > 1.8, errors


def test_past_the_shear_wave_a_cantilever_swings_with_the_coupled_step():
    """Past the solid's step (0.5 h / c_s) the elastic solve and the projection are solved
    as one system (State::coupled_solve): split, they grew a bending beam from about 1.5
    times the shear wave's crossing of a cell. At 2 ms, 31 times the crossing at h = H / 8,
    the beam swings as at the solid's step: its tip's mean over the first period within the
    issue's 3% of Timoshenko's deflection (measured -0.1%; -0.1% at 0.5 h / c_s too) and
    its deepest point at half the period within 5% (measured 1.93 times the deflection at
    0.500 T: backward Euler damps it a little; 2.00 at 0.5 h / c_s)."""
    from mpmflow.validation import solids

    n = 80
    period = f"time.end={solids.PERIOD:.6f}"
    sets = [
        "grid.spacing=0.0125",
        "time.dt=2e-3",
        period,
        f"output.interval={solids.PERIOD / n:.6f}",
    ]
    tips, _ = _cantilever(sets)
    assert abs(tips[:n].mean() - 1) < 0.03, tips[:n].mean()
    assert abs(np.argmax(tips) / n - 0.5) < 0.05, np.argmax(tips) / n


def _settled(h, dt, end=0.5):
    """The elastic layer of ``_layer`` under steps of dt (s), run to ``end``: the top row's
    mean downslope displacement over the static one (rho g sin(20 deg) H^2 / (2 G) = 84 um),
    and the largest particle speed at the end (m/s)."""
    H, th = 0.05, math.radians(20.0)
    sets = [
        f"domain.size=[{8 * h}, 0.1]",
        "domain.walls={y_min='bonded'}",
        "domain.periodic=[true, false]",
        f"grid.spacing={h}",
        f"bodies.0.max=[{8 * h}, {H}]",
        "bodies.0.particles_per_cell=2",
        "material.model='elastic'",
        "material.density=2000.0",
        "material.shear_modulus=1e5",
        f"physics.gravity={[9.81 * math.sin(th), -9.81 * math.cos(th)]}",
        f"time.dt={dt}",
        f"time.end={end}",
        "output.snapshots=false",
    ]
    sim = Simulation(load_case(ROOT / HYDRO, sets))
    x0 = sim.particles.x.copy()
    top = x0[:, 1] > H - h
    sim.run()
    static = 2000.0 * 9.81 * math.sin(th) * H**2 / (2 * 1e5)
    moved = (sim.particles.x[top, 0] - x0[top, 0]).mean()
    return moved / static, float(np.abs(sim.particles.v).max())


def test_the_coupled_step_settles_a_layer_at_steps_far_past_the_shear_wave():
    """At 2 ms, 11 and 23 times the shear wave's crossing of a cell at H / 10 and H / 20, the
    suddenly loaded layer settles (backward Euler damps its ringing) to its static shear:
    measured, top displacement over the static one 0.9950 and 0.9987, the largest speed at
    0.5 s 2e-12 m/s (with the split step, before: 1.152 and 1.077). Asserted: within 1% at
    both meshes, at rest to 1e-9 m/s."""
    for h in (0.005, 0.0025):
        ratio, speed = _settled(h, 2e-3)
        assert abs(ratio - 1) < 0.01 and speed < 1e-9, (h, ratio, speed)


def test_a_solid_with_obstacles_past_its_step_is_refused():
    """The coupled step takes no obstacles yet: past the solid's step (0.5 h / c_s) a case
    with one is refused, naming the step to take."""
    sets = ["material.model='elastic'", "material.shear_modulus=1e4", "time.dt=0.003"]
    load_case(ROOT / HYDRO, sets)  # without: the coupled step
    box = "obstacles=[{type='box', min=[0.0, 0.25], max=[0.02, 0.27]}]"
    with pytest.raises(CaseError, match=r"time.dt = .* above a solid's step.*no fixed obstacles"):
        load_case(ROOT / HYDRO, [*sets, box])


def test_schemes_and_runs_that_do_not_carry_the_stress_refuse_solids():
    """The explicit scheme carries no stress; over MPI ranks a solid runs at its own step
    (tests/parallel/test_split_solids.py), and its coupled step past the shear wave's, which is
    not split, is refused naming the longest step it takes."""
    with pytest.raises(CaseError, match="solver.scheme"):
        load_case(
            ROOT / HYDRO,
            ["material.model='elastic'", "solver.scheme='explicit'", "material.shear_modulus=1e4"],
        )
    case = load_case(
        ROOT / HYDRO,
        ["material.model='elastic'", "material.shear_modulus=1e4", "domain.walls='bonded'"],
    )
    found = " ".join(refusals(case))
    assert "solid" not in found and "bonded walls" in found
    # G = 1e6 Pa: the shear wave's step 0.5 h / sqrt(G / rho) = 0.158 ms, the case's dt 1 ms
    stiff = load_case(ROOT / HYDRO, ["material.model='elastic'", "material.shear_modulus=1e6"])
    found = " ".join(refusals(stiff))
    assert "coupled elastic-pressure solve" in found and "time.dt to at most 0.000158 s" in found


def test_a_solids_snapshots_and_checkpoints_carry_its_stress(tmp_path):
    """The VTU snapshot holds the deviatoric stress (9 components), the plastic strain and
    the yielding flag; a run resumed from a checkpoint continues with the same stress, so it
    ends where an uninterrupted run ends, bit for bit."""
    import shutil

    import meshio

    sets = ["material.model='elastic'", "material.shear_modulus=1e4", "time.end=0.05"]
    sets += ["physics.gravity=[3.0, -9.81]", "output.snapshot_interval=0.05"]
    sets += ["checkpoint.interval=0.02"]
    whole = Simulation(load_case(ROOT / HYDRO, sets), out_dir=tmp_path / "whole")
    whole.run()
    mesh = meshio.read(sorted((tmp_path / "whole").glob("*.vtu"))[-1])
    stress = mesh.point_data["deviatoric_stress"].reshape(-1, 3, 3)
    assert np.array_equal(stress[:, :2, :2], whole.history["stress"])
    assert np.abs(stress).max() > 0.0 and "plastic_strain" in mesh.point_data
    assert "yielding" in mesh.point_data
    out = tmp_path / "parts"
    shutil.copytree(tmp_path / "whole", out)  # resuming truncates the later outputs
    rest = Simulation.resume(load_case(ROOT / HYDRO, sets), out, out / "checkpoint_000000040.npz")
    rest.run()
    assert np.array_equal(rest.history["stress"], whole.history["stress"])
    assert np.array_equal(rest.particles.x, whole.particles.x)
