"""Obstacles on prescribed paths over MPI ranks (issue 44 on issue 42's split step), on one
process and under ``mpirun -n 2`` (``make test-mpi``): each rank places the bodies on its
own grid in the domain's frame, with two ghost layers (``subgrid.ghost_layers``), and the
force on them is summed over the cut cells each rank owns (a solid's tools: over the
nodes each owns, tests/parallel/test_split_solids.py).

Tolerances: every system is solved to a relative residual of 1e-8, so after 150 steps the
towed box's particles follow one process to far better than 1e-8 m (measured on 2 ranks:
7.8e-11 m, 5.8e-9 m/s) and its force to 5e-8 N/m of 14 N/m (bound 1e-5 N/m); with one ghost
layer the box crossing the rank boundary put them 1.3 mm and 0.13 m/s apart, and its force
77 N/m."""

import numpy as np
import pytest
from conftest import EXAMPLES

from mpmflow import load_case
from mpmflow.simulation import Simulation

pytest.importorskip("petsc4py")
pytest.importorskip("mpi4py")

from splitting import alone, split, whole  # noqa: E402

from mpmflow.parallel.comm import world  # noqa: E402
from mpmflow.parallel.support import refusals  # noqa: E402

TOW = "obstacles=[{type='box', min=[0.055, 0.035], max=[0.085, 0.065], motion={type='velocity', velocity=[0.2, 0.0], rate=1.0}}]"  # noqa: E501


# water 0.1 m deep in a tank 0.2 m wide, around the obstacles
TANK = ["domain.size=[0.2, 0.15]", "bodies.0.max=[0.2, 0.1]", "bodies.0.around_obstacles=true"]


def tank(obstacles: str) -> Simulation:
    over = [*TANK, "output.snapshots=false", "time.end=0.3", obstacles]
    return Simulation(load_case(EXAMPLES / "hydrostatic.toml", over))


def towed() -> Simulation:
    """The tank with a 3 x 3 cm box towed through it at 0.2 m/s from x = 0.055 m: the boxes'
    first cut, across x at the tank's middle, lies in its way."""
    return tank(TOW)


def test_a_box_towed_across_the_rank_boundary_follows_one_process():
    one = alone(towed())
    many = split(towed())
    forces = []
    for _ in range(15):  # chunks as a run's output times make them (the boxes split again)
        one.scheme.advance(one.dt, 10)
        many.scheme.advance(many.dt, 10)
        forces.append((one.scheme.body_values()[0][0], many.scheme.body_values()[0][0]))
    if world().size > 1:  # the box (0.085 -> 0.115 m at its front) crossed a cut
        assert many.scheme.boxes.ghost == 2
        cuts = {int(c) * 0.01 for c in many.scheme.boxes.hi[:, 0] if c < 20}
        assert any(0.055 < c < 0.115 for c in cuts)
    P = whole(many)[0]
    assert np.abs(P.x - one.particles.x).max() < 1e-8  # m
    assert np.abs(P.v - one.particles.v).max() < 1e-6  # m/s
    a, b = np.array(forces).transpose(1, 0, 2)
    assert np.abs(a).max() > 1.0  # N/m: the water pushes back
    assert np.abs(b - a).max() < 1e-5  # N/m
    # the pose in the domain's frame on every rank
    assert np.allclose(many.scheme.body_values()[2][0, :2], [0.1, 0.05], atol=1e-12)


FREE = (
    "obstacles=[{type='box', min=[0.08, 0.085], max=[0.12, 0.125], "
    "motion={type='free', density=500.0}}]"
)


def floating() -> Simulation:
    """The same tank with a free box of density 500 kg/m^3 released 5 mm above the draft its
    weight gives (half its 4 cm), straddling the tank's middle: the boxes' first cut."""
    return tank(FREE)


def heaves(one: Simulation, many: Simulation, chunks: int) -> tuple[np.ndarray, np.ndarray]:
    """The free body's pivot height (m) after each of ``chunks`` chunks of 10 steps, on one
    process and over the ranks, checking that every rank holds the same body and that the
    body (x 0.08-0.12 m) straddles one of the boxes' cuts."""
    heave = []
    for _ in range(chunks):
        one.scheme.advance(one.dt, 10)
        many.scheme.advance(many.dt, 10)
        a, b = one.scheme.body_values()[2], many.scheme.body_values()[2]
        heave.append((a[0, 1], b[0, 1]))
        assert np.array_equal(b, world().bcast(b))  # the same body on every rank
    if world().size > 1:
        cuts = {int(c) * 0.01 for c in many.scheme.boxes.hi[:, 0] if c < 20}
        assert any(0.08 < c < 0.12 for c in cuts)
    a, b = np.array(heave).T
    return a, b


def test_a_free_body_across_the_rank_boundary_follows_one_process():
    """A free body's coupling to the pressure (State::couple_bodies: nq more solves and an
    nq x nq system) sums its products over the rows each rank owns, so every rank moves the
    body alike; its state goes from chunk to chunk (each split builds a new core). After 150
    steps it follows one process to the solves' tolerance, as the towed box does."""
    one, many = alone(floating()), split(floating())
    a, b = heaves(one, many, 15)
    assert a[0] - a.min() > 1e-3  # m: it sank towards its draft
    assert np.abs(b - a).max() < 1e-8  # m
    P = whole(many)[0]
    assert np.abs(P.x - one.particles.x).max() < 1e-8  # m
    assert np.abs(P.v - one.particles.v).max() < 1e-6  # m/s


# a block on the floor across the tank's middle (the boxes' first cut), and a free box of
# density 1500 kg/m^3 2 cm above it, straddling the cut too
LANDING = (
    "obstacles=[{type='box', min=[0.06, 0.0], max=[0.14, 0.03]}, "
    "{type='box', min=[0.08, 0.05], max=[0.12, 0.07], motion={type='free', density=1500.0}}]"
)


def landing() -> Simulation:
    """The tank with a free box that sinks onto a fixed block, both across the cut."""
    return tank(LANDING)


def test_a_free_body_lands_on_a_fixed_obstacle_across_the_rank_boundary():
    """A free body's contact with a fixed obstacle reads the obstacle's surface where each
    surface point's cell is owned (BodyTables::contact: that rank interpolates its phi and
    the values are summed over the ranks), so every rank takes the same contacts and holds
    the same body (with each rank reading its own grid, this test did not end within 10
    minutes on 2 ranks). The box falls 2 cm, lands on the block and rests there, and over
    the 200 steps it follows one process to the solves' tolerance, as the floating box does
    (measured on 2 ranks: 1e-13 m).

    Its corners start on nodes: before a node within rounding of a body's surface was taken
    as on it (BodyTables::ON_SURFACE), the sign of that rounding decided those nodes' cells,
    and the ranks, whose sums round otherwise, turned the box at up to 3e-3 rad/s off one
    process's from the first steps, as a pose 1e-13 m off did on one process."""
    one, many = alone(landing()), split(landing())
    a, b = heaves(one, many, 20)
    # it fell 2 cm and rests on the block's top (y = 0.03 m): its centre 1 cm above it, to
    # the contact's touching distance and the rounding of the rest (1e-3 h is 5e-6 m)
    assert a[0] - a[-1] > 0.015  # m: it fell
    assert a[-1] == pytest.approx(0.04, abs=1e-5)
    assert np.abs(b - a).max() < 1e-8  # m
    P = whole(many)[0]
    assert np.abs(P.x - one.particles.x).max() < 1e-8  # m
    assert np.abs(P.v - one.particles.v).max() < 1e-6  # m/s


def test_paths_and_free_bodies_are_not_refused_on_ranks():
    """A path is split over ranks for a fluid and for a solid's tools
    (tests/parallel/test_split_solids.py), and so is a free body, beside fixed obstacles
    too (above)."""
    base = TANK
    for bodies in (FREE, LANDING):
        case = load_case(EXAMPLES / "hydrostatic.toml", [*base, bodies])
        assert refusals(case) == []
    solid = ["material.model='elastic'", "material.shear_modulus=1e4"]
    case = load_case(EXAMPLES / "hydrostatic.toml", [*base, *solid, TOW])
    assert refusals(case) == []
    case = load_case(EXAMPLES / "hydrostatic.toml", [*base, TOW])
    assert refusals(case) == []
