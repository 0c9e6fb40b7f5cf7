"""The projection scheme split over MPI ranks (``parallel.scheme``), on one process and under
``mpirun -n 2`` (``make test-mpi``): the same particles as the one-process run to the
pressure solver's tolerance, the column at rest exact with a rank boundary through the
water and through an obstacle, and the cases it does not split refused by name.

Tolerances: the pressure solves converge to a relative residual of 1e-8 (PETSc's CG here,
the core's multigrid there), so after 300 steps with impacts the particles agree to far
better than 1e-8 m (measured: 1.2e-9 m on 2 ranks, 1.0e-10 m on 4); the column at rest is
held to the one-process criteria of tests/boundaries (1e-8 m/s, rho g (H - y) to 1e-6)."""

import numpy as np
import pytest
from conftest import EXAMPLES

from mpmflow import load_case
from mpmflow.errors import CaseError, SolverError
from mpmflow.simulation import Simulation

pytest.importorskip("petsc4py")
pytest.importorskip("mpi4py")

from splitting import alone, split, whole  # noqa: E402

from mpmflow.parallel.comm import world  # noqa: E402
from mpmflow.parallel.support import distributed  # noqa: E402

RHO, G = 1000.0, 9.81


def dam_break(transfer: str = "flip") -> Simulation:
    case = load_case(
        EXAMPLES / "dam_break.toml",
        ["time.end=0.3", "solver.volume_correction=0", f"solver.transfer={transfer}"],
    )
    return Simulation(case)


@pytest.mark.parametrize("transfer", ["flip", "apic"])
def test_the_dam_break_over_the_ranks_is_the_one_process_run(transfer):
    one = alone(dam_break(transfer))
    many = split(dam_break(transfer))
    a = one.scheme.advance(one.dt, 300)
    b = many.scheme.advance(many.dt, 300)
    P, carried = whole(many)
    assert np.abs(P.x - one.particles.x).max() < 1e-8  # m
    assert np.abs(P.v - one.particles.v).max() < 1e-6  # m/s
    # every particle comes back once, with its own mass and volume
    assert np.array_equal(P.mass, one.particles.mass)
    assert np.array_equal(P.volume, one.particles.volume)
    # the walls let go where they do on one process (impact at 0.22 s)
    assert b.released == a.released > 0 and b.solves == a.solves
    assert b.unknowns == a.unknowns
    assert np.abs(many.scheme.p_node - one.scheme.p_node).max() < 1e-6 * RHO * G * 0.228
    if transfer == "apic":  # the affine matrices travel with their particles (1/s):
        # C_p sums v_i grad N_i over 2^D nodes (|grad N_i| <= 1/h), and a light node's
        # velocity differs more than the particles' (measured: 1.7e-3 1/s with BoomerAMG,
        # 4.7e-4 with GAMG); bound: the velocity across a cell it implies, C h, within ten
        # times the particles' 1e-6 m/s
        assert np.abs(carried["affine"] - one.scheme.affine).max() * 0.004 < 1e-5


def test_the_volume_correction_over_the_ranks_is_the_one_process_one():
    """The dam break with the volume correction (every 2 ms), every system solved to
    1e-10 on both sides, so that what the two solvers leave (1e-8 of the residual) does not
    hide a fault of the split."""
    case = load_case(EXAMPLES / "dam_break.toml", ["time.end=0.3", "solver.tolerance=1e-10"])
    one = alone(Simulation(case))
    many = split(Simulation(case))
    a = one.scheme.advance(one.dt, 300)
    b = many.scheme.advance(many.dt, 300)
    assert a.unknowns == b.unknowns and a.released == b.released
    assert many.scheme.volume.iterations > 0
    P = whole(many)[0]
    assert np.abs(P.x - one.particles.x).max() < 1e-8  # m
    assert np.array_equal(P.volume, one.particles.volume)


@pytest.mark.parametrize(
    "example, steps",
    [("bingham_slump.toml", 200), ("granular_collapse.toml", 200)],
    ids=["bingham", "mu(I)"],
)
def test_a_viscous_material_over_the_ranks_is_the_one_process_run(example, steps):
    """The viscous predictor's system solved by PETSc over the ranks: the Bingham slump
    (rough floor, the viscosity capped in the unyielded core, APIC transfers) and the granular
    column (mu(I), its viscosity set by the pressure, PIC) follow one process to the solvers'
    tolerance (measured after 200 steps on 2 and 4 ranks: 6.3e-11 m and 2.3e-9 m/s at most,
    808 capped cell-steps on both; with the slump's earlier PIC mud, 4.5e-10 m and 1.9e-8
    m/s; before the ranks took their owners' starting velocity at the local grid's edge,
    3e-6 m and 4e-5 m/s)."""
    case = load_case(EXAMPLES / example, ["time.end=1", "output.snapshots=false"])
    one = alone(Simulation(case))
    many = split(Simulation(case))
    a = one.scheme.advance(one.dt, steps)
    b = many.scheme.advance(many.dt, steps)
    assert b.viscous_iterations > 0
    assert b.capped == a.capped  # the cells held at max_viscosity, each counted once
    P = whole(many)[0]
    assert np.abs(P.x - one.particles.x).max() < 1e-8  # m
    assert np.abs(P.v - one.particles.v).max() < 1e-6  # m/s


def at_rest(obstacle: bool) -> Simulation:
    """A column 0.1 m deep in a tank 0.2 m wide: the boxes' first cut is across x, through
    the middle of the water (and of the obstacle on the floor, faces off the grid lines)."""
    over = [
        "domain.size=[0.2, 0.15]",
        "bodies.0.max=[0.2, 0.1]",
        "time.end=0.3",
        "output.snapshots=false",
    ]
    if obstacle:
        over += [
            "obstacles=[{type='box', min=[0.0837, 0.0], max=[0.1163, 0.0517]}]",
            "bodies.0.around_obstacles=true",
        ]
    return split(Simulation(load_case(EXAMPLES / "hydrostatic.toml", over)))


@pytest.mark.parametrize("obstacle", [False, True], ids=["column", "column round a box"])
def test_the_column_at_rest_is_exact_across_the_rank_boundaries(obstacle):
    sim = at_rest(obstacle)
    sim.run()
    boxes = sim.scheme.boxes
    if world().size > 1:  # a box boundary crosses the water (and the obstacle)
        cuts = {int(c) * 0.01 for c in boxes.hi[:, 0] if c < boxes.cells[0]}
        assert any(0.0837 < c < 0.1163 for c in cuts)
    P = sim.particles
    assert np.nanmax(sim.series("max_speed")) <= (1e-6 if obstacle else 1e-8)
    exact = RHO * G * (0.1 - P.x[:, 1])
    assert np.max(np.abs(P.pressure - exact)) <= 1e-6 * RHO * G * 0.1


@pytest.mark.parametrize(
    "override, named",
    [
        ("solver.linear_solver=amg", "solver.linear_solver"),
        ("domain.periodic=[true,false]", "domain.periodic"),
        ("solver.scheme=explicit time.dt=2e-6", "solver.scheme"),
    ],
)
def test_what_is_not_split_yet_is_refused_by_name(override, named):
    over = [*override.split(), "domain.size=[0.416, 0.44]"]
    case = load_case(EXAMPLES / "dam_break.toml", over)
    with pytest.raises(CaseError, match=named.replace(".", r"\.")):
        distributed(case, None, None)  # type: ignore[arg-type]


def test_a_column_cut_across_its_depth_is_not_a_sealed_pocket():
    """The tall column: the boxes' first cut is across y, so the lower rank's rows touch no
    free surface of their own; joined with the upper rank's they do (no pocket), and the
    column stays at rest."""
    over = ["time.end=0.1", "output.snapshots=false"]
    sim = split(Simulation(load_case(EXAMPLES / "hydrostatic.toml", over)))
    sim.run()
    if world().size > 1:
        assert sim.scheme.boxes.lo[:, 1].max() > 0  # a cut across the depth
    assert np.nanmax(sim.series("max_speed")) <= 1e-8


LID = """
title = "water sealed under a lid across the tank, more water above it"
[domain]
size = [0.4, 0.3]
[grid]
spacing = 0.01
[[bodies]]
type = "box"
min = [0.0, 0.0]
max = [0.4, 0.2]
particles_per_cell = 2
around_obstacles = true
[[obstacles]]
type = "box"
min = [0.0, 0.1]
max = [0.4, 0.12]
[physics]
gravity = [0.0, -9.81]
[time]
dt = 1e-3
end = 0.01
[output]
interval = 0.01
snapshots = false
[solver]
volume_correction = 0
"""


def test_water_sealed_across_the_ranks_is_refused(tmp_path):
    """The layer under the lid spans the cut between the boxes: each rank holds part of a
    pocket, and only their join shows it has no free surface."""
    path = tmp_path / "lid.toml"
    path.write_text(LID)
    sim = split(Simulation(load_case(path)))
    with pytest.raises(SolverError, match="sealed off"):
        sim.scheme.advance(sim.dt, 1)
    if world().size > 1:
        assert np.any(sim.scheme.boxes.hi[:, 0] < 40)  # the cut crosses the layer


def test_a_pressure_solve_that_fails_names_the_worst_node_on_every_rank():
    case = load_case(
        EXAMPLES / "dam_break.toml",
        ["solver.max_iterations=1", "solver.tolerance=1e-12", "time.end=0.01"],
    )
    sim = split(Simulation(case))
    with pytest.raises(SolverError, match=r"did not converge.*largest residual at node \(0\.\d"):
        sim.scheme.advance(sim.dt, 2)


def test_steps_set_by_the_flow_are_the_one_process_steps():
    """time.dt = "auto": the step from the largest speed over all ranks, the last two
    steps of a span shortened to land on its end, as the core's advance_span takes them;
    the volume correction after each 2 ms of flow."""
    over = ["time.end=0.3", 'time.dt="auto"', "time.courant=0.5"]
    case = load_case(EXAMPLES / "dam_break.toml", over + ["solver.volume_correction=0"])
    one = alone(Simulation(case))
    many = split(Simulation(case))
    for _ in range(3):  # three output intervals of 0.1 s
        a = one.scheme.advance(0.01, 10)
        b = many.scheme.advance(0.01, 10)
        assert b.steps == a.steps > 10
        # dt = C h / the largest speed: the speeds agree to 1e-6 m/s at about 1 m/s
        assert (b.dt_min, b.dt_max) == pytest.approx((a.dt_min, a.dt_max), rel=1e-6)
    assert np.abs(whole(many)[0].x - one.particles.x).max() < 1e-8
    corrected = split(Simulation(load_case(EXAMPLES / "dam_break.toml", over)))
    corrected.scheme.advance(0.01, 10)
    assert corrected.scheme.volume.iterations > 0  # the correction ran on its interval


def test_no_rank_holds_the_whole_run_and_the_measures_are_the_whole_runs():
    """After a run every rank holds its own particles only (each particle on one rank,
    sorted by its number in the run), and the measures of a timeseries row, combined over
    the ranks (diagnostics.parts), are those of the whole run gathered: the cells' fractions
    (front, height, volume) exactly, the sums over particles to their rounding."""
    from mpmflow.cells import bin_particles
    from mpmflow.diagnostics.measures import front_and_height, pressure_noise, totals

    over = ["time.end=0.2", "solver.volume_correction=0", "output.snapshots=false"]
    sim = split(Simulation(load_case(EXAMPLES / "dam_break.toml", over)))
    sim.run()
    comm = world()
    P, _ = whole(sim)
    counts = comm.allgather(sim.particles.count)
    assert sum(counts) == P.count == sim.count0
    if comm.size > 1:
        assert max(counts) < P.count
    assert np.all(np.diff(sim.ids) > 0)
    assert np.array_equal(P.x[sim.ids], sim.particles.x)
    row = sim.measure()
    bins = bin_particles(sim.grid, P)
    front, height = front_and_height(sim.grid, bins.theta)
    assert (row["front"], row["height"]) == (front, height)
    assert row["max_particles_per_cell"] == int(np.diff(bins.start).max())
    t = totals(P, sim.case.physics.gravity)
    for name, value in [
        ("kinetic_energy", t.kinetic),
        ("potential_energy", t.potential),
        ("max_speed", t.max_speed),
        ("max_pressure", t.max_pressure),
        ("pressure_noise", pressure_noise(sim.grid, P)),
    ]:
        assert row[name] == pytest.approx(value, rel=1e-12), name
    assert sim.totals().fastest == t.fastest  # its number in the run


def test_probes_and_the_centre_of_mass_over_the_ranks_read_what_one_process_reads():
    """Pressure probes (their windows' particles joined over the ranks, some windows across
    the boxes' cut), level gauges (on the cells' fractions summed over the ranks) and the
    centre of mass over 0.15 s of the dam break: one process's readings, to the pressure
    solves' tolerance (1e-8 of their residual: 1e-6 of rho g H in the pressures)."""
    probes = ", ".join(
        [
            *(
                f"{{name='p{k}', quantity='pressure', position=[{x}, {y}]}}"
                for k, (x, y) in enumerate([(0.0, 0.05), (0.03, 0.02), (0.057, 0.116), (0.1, 0.0)])
            ),
            "{name='h0', quantity='level', position=[0.05, 0.0]}",
            "{name='h1', quantity='level', position=[0.2, 0.0], gauge='first_drop'}",
        ]
    )
    over = [
        "time.end=0.15",
        "solver.volume_correction=0",
        "output.snapshots=false",
        f"probes=[{probes}]",
        "output.centre_of_mass=true",
    ]
    case = load_case(EXAMPLES / "dam_break.toml", over)
    many = split(Simulation(case))
    many.scheme.parted()  # the first split
    if world().size == 2:  # the first cut, across the column at y = 0.116 m: p2 on it
        assert many.scheme.boxes.hi[0, 1] * many.grid.spacing == pytest.approx(0.116)
    many.run()
    one = alone(Simulation(case))
    one.run()
    for p in case.probes:
        a, b = many.probe_series(p.name), one.probe_series(p.name)
        assert a.size == b.size == 16
        scale = RHO * G * 0.228 if p.quantity == "pressure" else 0.228
        assert np.abs(a - b).max() <= 1e-6 * scale, p.name
    assert np.nanmax(one.probe_series("p0")) > 0.5 * RHO * G * 0.228  # the sensors are wet
    centres = [s.builtin_writers["centre_of_mass"].buffer for s in (many, one)]
    for axis in ("x_c", "y_c"):
        assert np.abs(centres[0].column(axis) - centres[1].column(axis)).max() < 1e-8  # m


@pytest.mark.parametrize(
    "example, over",
    [
        ("obstacle_2d.toml", []),  # a polygon body round two obstacles
        ("hump.toml", []),  # a box body round an obstacle, hydrostatic
        ("dam_break.toml", ["bodies.0.surface_amplitude=0.01"]),  # a cosine top
        ("dam_break_3d.toml", []),
    ],
)
def test_each_rank_seeds_its_own_particles_as_one_process_numbers_them(monkeypatch, example, over):
    """parallel.seeding: every rank walks the lattice in chunks (here of 1000 points, so
    that each body takes many) and keeps its own particles; each particle is on one rank,
    with the number one process gives it, at the same place, with the same mass, volume
    and velocity, and the same starting pressure to its rounding."""
    from mpmflow.geometry.seeding import build_particles
    from mpmflow.grid import Grid
    from mpmflow.parallel import seeding

    monkeypatch.setattr(seeding, "CHUNK", 1000)
    case = load_case(EXAMPLES / example, over)
    grid = Grid.of_case(case)
    whole = build_particles(case, grid)
    comm = world()
    part, numbers = seeding.seed_part(case, grid, comm)
    every = np.sort(np.concatenate(comm.allgather(numbers)))
    assert np.array_equal(every, np.arange(whole.count))
    assert np.all(np.diff(numbers) > 0)
    for name in ("x", "v", "mass", "volume"):
        assert np.array_equal(getattr(part, name), getattr(whole, name)[numbers]), name
    scale = max(float(np.abs(whole.pressure).max()), 1.0)
    assert np.abs(part.pressure - whole.pressure[numbers]).max() <= 1e-12 * scale


def test_particles_left_out_are_renumbered_as_one_process_numbers_those_kept():
    from mpmflow.parallel.seeding import renumbered

    comm = world()
    n = 40
    mine = np.arange(comm.rank, n, comm.size)  # each rank's numbers, interleaved
    out = np.isin(mine, [3, 4, 17, 30, 39])
    kept = renumbered(comm, mine, out)
    whole = np.delete(np.arange(n), [3, 4, 17, 30, 39])  # one process's, in order
    expected = np.searchsorted(whole, mine[~out])  # the kept ones' places among them
    assert np.array_equal(kept, expected)
    every = np.sort(np.concatenate(comm.allgather(kept)))
    assert np.array_equal(every, np.arange(n - 5))
