"""The step's public phases, the seam of a domain decomposition (issue 28,
docs/design/mpi.md, section 2): scatter + classify are predict, correct + to_particles are
finish, renumber numbers as classify does, Options.pockets leaves the sealed pockets to the
caller, and the State's lower corner is where particles are put back inside."""

import numpy as np
import pytest
from conftest import EXAMPLES, POCKET_2D, make_case

from mpmflow import Simulation, load_case, state
from mpmflow.boundaries import walls

DT = 1e-3

# the arrays scatter and classify write, and the system pressure_matrix and pressure_rhs
# assemble from them
SCATTERED = ("node_mass", "node_vol", "v_old", "v_star", "node_f", "theta")
SYSTEM = ("node_row", "rows", "matrix_cols", "matrix_vals", "rhs", "anchored")


def dam_break(settings=(), steps=30):
    """The dam break on a 0.01 m grid after ``steps`` steps (the column falling)."""
    case = load_case(
        EXAMPLES / "dam_break.toml", ["grid.spacing=0.01", "output.snapshots=false", *settings]
    )
    sim = Simulation(case)
    sim.scheme.advance(DT, steps)
    return sim


def pocket(tmp_path, steps=5):
    path = tmp_path / "pocket.toml"
    path.write_text(POCKET_2D)
    sim = Simulation(load_case(path))
    sim.scheme.advance(DT, steps)
    return sim


def arrays(sim):
    P = sim.particles
    return [P.x, P.v, P.mass, P.volume, P.pressure]


def copies(sim):
    return [a.copy() for a in arrays(sim)]


def assembled(core, O, correct):
    assert core.pressure_matrix(O)
    core.pressure_rhs(O)
    names = SCATTERED + SYSTEM + (("cell_vol",) if correct else ())
    return {name: getattr(core, name).copy() for name in names}


@pytest.mark.parametrize("correct", [False, True], ids=["step", "volume-correction step"])
def test_scatter_then_classify_give_predicts_system(correct):
    """Two runs of the same steps: one predicts, the other scatters and classifies into
    arrays overwritten with garbage first (so every value the system reads is the phases')."""
    one, two = dam_break(), dam_break()
    O = one.scheme.options(DT)
    n = one.scheme.core.predict(*arrays(one), O, correct)
    expected = assembled(one.scheme.core, O, correct)
    core = two.scheme.core
    assert core.cell_vol.size == np.prod(two.grid.cells)  # the dam break corrects its volume
    for name in SCATTERED + (("cell_vol",) if correct else ()):
        getattr(core, name)[...] = np.nan
    core.node_row[...] = 7
    core.scatter(*arrays(two), O, correct)
    assert core.classify(*arrays(two), O) == n > 0
    got = assembled(core, O, correct)
    for name, value in expected.items():
        assert np.array_equal(got[name], value), name


def test_classify_refuses_particles_scatter_did_not_bin():
    sim = dam_break(steps=1)
    O = sim.scheme.options(DT)
    sim.scheme.core.scatter(*arrays(sim), O, False)
    with pytest.raises(ValueError, match="the particles the last scatter binned"):
        sim.scheme.core.classify(*[a[:10] for a in arrays(sim)], O)


def test_the_views_are_the_states_arrays():
    sim = dam_break(steps=1)
    core, O = sim.scheme.core, sim.scheme.options(DT)
    n = core.predict(*arrays(sim), O, False)
    nn, nc, D = int(np.prod(np.add(sim.grid.cells, 1))), int(np.prod(sim.grid.cells)), 2
    shapes = {name: getattr(core, name).shape for name in SCATTERED + ("node_row", "cell_vol")}
    assert shapes == {
        "node_mass": (nn,),
        "node_vol": (nn,),
        "v_old": (nn, D),
        "v_star": (nn, D),
        "node_f": (nn,),
        "theta": (nc,),
        "node_row": (nn,),
        "cell_vol": (nc,),  # the volume correction is on
    }
    assert core.node_row.dtype == np.int64 and core.anchored.dtype == np.bool_
    # written through: the mass seen by the next phase is the one written here
    core.node_mass[0] = 5.0
    assert core.node_mass[0] == 5.0
    assert core.pressure_matrix(O)
    assert core.anchored.shape == (n,) and core.anchored.any() and not core.anchored.all()


def test_renumber_right_after_classify_changes_nothing_and_a_row_taken_out_goes():
    sim = dam_break()
    core, O = sim.scheme.core, sim.scheme.options(DT)
    n = core.predict(*arrays(sim), O, False)
    rows, node_row = core.rows.copy(), core.node_row.copy()
    assert core.renumber() == n
    assert np.array_equal(core.rows, rows) and np.array_equal(core.node_row, node_row)
    k = n // 2
    core.node_row[rows[k]] = -1
    assert core.renumber() == n - 1
    assert np.array_equal(core.rows, np.delete(rows, k))
    expected = node_row.copy()
    expected[rows[k]] = -1
    expected[rows[k + 1 :]] -= 1
    assert np.array_equal(core.node_row, expected)
    assert core.pressure_matrix(O)
    assert core.matrix_cols.shape == (n - 1, 9)


def test_renumber_gives_an_image_its_masters_row():
    """x periodic: the image plane x = L shares the rows of the plane x = 0, whose entries
    decide (an image's own entry is ignored, as classify_nodes ignores it)."""
    sim = dam_break(["domain.size=[0.48, 0.44]", "domain.periodic=[true, false]"])
    core, O = sim.scheme.core, sim.scheme.options(DT)
    n = core.predict(*arrays(sim), O, False)
    nx = int(sim.grid.cells[0]) + 1
    plane = core.node_row.reshape(-1, nx)
    assert np.array_equal(plane[:, -1], plane[:, 0]) and (plane[:, 0] >= 0).any()
    rows, node_row = core.rows.copy(), core.node_row.copy()
    assert core.renumber() == n
    assert np.array_equal(core.rows, rows) and np.array_equal(core.node_row, node_row)
    j = int(np.flatnonzero(plane[:, 0] >= 0)[0])  # a row of the master plane
    plane[j, -1] = -1  # the image alone: nothing changes
    assert core.renumber() == n and np.array_equal(core.node_row, node_row)
    plane[j, 0] = -1  # the master: both go
    assert core.renumber() == n - 1
    assert plane[j, 0] == plane[j, -1] == -1
    assert np.array_equal(plane[:, -1], plane[:, 0])


def test_options_pockets_false_leaves_the_sealed_pockets(tmp_path):
    sim = pocket(tmp_path)
    core, O = sim.scheme.core, sim.scheme.options(DT)
    assert O.pockets is True and state.step_options(2).pockets is True
    assert state.step_options(2, pockets=False).pockets is False
    core.predict(*arrays(sim), O, False)
    assert core.pressure_matrix(O) and core.pockets >= 1
    matrix = core.matrix_vals.copy()
    O.pockets = False
    assert core.pressure_matrix(O) and core.pockets == 0
    # the pockets' held rows lose their couplings only when they are held
    assert not np.array_equal(core.matrix_vals, matrix)


@pytest.mark.parametrize("case", ["flip", "apic", "obstacle", "volume correction"])
def test_correct_then_to_particles_is_finish(case, tmp_path):
    """finish and its parts, from the same predicted step, move copies of the particles
    alike; to_particles on the first m particles moves them as it moves all of them."""
    if case == "obstacle":
        sim = pocket(tmp_path)
    else:
        sim = dam_break(["solver.transfer=apic"] if case == "apic" else [])
    core, O = sim.scheme.core, sim.scheme.options(DT)
    correct = case == "volume correction"
    affine = sim.scheme.affine
    core.predict(*arrays(sim), O, correct, affine=affine)
    one = copies(sim)
    one_affine = None if affine is None else affine.copy()
    report = state.Report()
    assert core.finish(*one, O, correct, report, affine=one_affine) == state.OK
    two = copies(sim)
    two_affine = None if affine is None else affine.copy()
    core.correct(O)
    moved = core.to_particles(*two, O, correct, affine=two_affine)
    assert moved == report.moved
    for a, b in zip(one, two):
        assert np.array_equal(a, b)
    if affine is not None:
        assert np.array_equal(one_affine, two_affine)
    m = len(sim.particles.x) // 3
    three = [a[:m].copy() for a in arrays(sim)]
    core.to_particles(*three, O, correct, affine=None if affine is None else affine[:m].copy())
    for a, b in zip(one, three):
        assert np.array_equal(a[:m], b)
    # the step really moved the particles, and the volume correction's faces moved them too
    assert not np.array_equal(one[0], sim.particles.x)
    if correct:
        four = copies(sim)
        core.to_particles(*four, O, False)
        assert not np.array_equal(four[0], one[0])


def put_back_state(lower, margin):
    """A State on a 0.1 m x 0.3 m grid (0.01 m) with the given lower corner."""
    case = make_case()
    sim = Simulation(case)
    core = state.step_state(
        sim.grid,
        walls.of_case(case, sim.grid).as_tuple(),
        sim.scheme.solids,
        np.zeros((0, 0, 0, 0)),
        margin,
        False,
        False,
        lower=lower,
    )
    return sim, core


@pytest.mark.parametrize("lower", [None, [0.03, 0.0]], ids=["0", "0.03"])
def test_a_particle_that_left_below_lower_is_put_back_at_lower_plus_margin(lower):
    """One particle at x = 0.035 m moved by -0.01 m: inside the box [0, ...] it stays at
    0.025 m; with lower = 0.03 m it left, and is put back at lower + margin (its mirror
    0.035 m is nearer the wall than the margin 0.008 m)."""
    margin = 0.008
    sim, core = put_back_state(lower, margin)
    O = state.step_options(2, dt=0.01, flip=1.0)
    x = np.array([[0.035, 0.15]])
    v = np.array([[-1.0, 0.0]])
    P = [x, v, np.array([1.0]), np.array([1e-4]), np.array([0.0])]
    core.scatter(*P, O, False)
    core.classify(*P, O)
    core.v_new[...] = [-1.0, 0.0]  # every node: the particle moves by -0.01 m along x
    core.v_old[...] = [-1.0, 0.0]
    core.p_node[...] = 0.0
    moved = core.to_particles(*P, O, False)
    if lower is None:
        assert moved == 0 and x[0, 0] == pytest.approx(0.025) and v[0, 0] == -1.0
    else:
        assert moved == 1 and x[0, 0] == 0.03 + margin and v[0, 0] == 0.0
    assert x[0, 1] == 0.15
