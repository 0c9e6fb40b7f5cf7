"""Solids over MPI ranks (issue 43 on issue 42's split step), on one process and under
``mpirun -n 2`` (``make test-mpi``): the stress history travels with the particles (halo and
migration), the cells' pressure is solved by PETSc over the ranks with the ghost layer's
rows and gradients their owners', and a run follows the one-process run to the solvers'
tolerance.

Tolerances: every system is solved to a relative residual of 1e-8 (PETSc's CG here, the
core's multigrid there). The column at rest keeps the one-process criteria of
tests/materials/test_solids.py (1e-9 m/s, the pressure within 1e-8 of rho g H, the stress
under 1e-5 Pa; measured on 2 ranks: 1.5e-10 m/s, 5e-10 of rho g H). The collapsing
Drucker-Prager column after 500 steps of 0.1 ms, measured on 2 ranks: 5.8e-12 m, 2.5e-9 m/s,
1.2e-4 Pa of its deviatoric stress (hundreds of Pa), 5.5e-9 of plastic strain (up to 1.1),
1.4e-4 Pa of the cells' pressure; the bounds hold these with a margin of 10 to 1000 for the
solvers' rounding on other machines, and each lies far below what a fault of the split
made (before the ghost layer took its owners' pressure gradients, which the yield reads:
2.6 mm and 0.28 m/s after 1000 steps)."""

import numpy as np
import pytest
from conftest import EXAMPLES

from mpmflow import load_case
from mpmflow.simulation import Simulation

pytest.importorskip("petsc4py")
pytest.importorskip("mpi4py")

from splitting import alone, split, whole  # noqa: E402

from mpmflow.parallel.comm import world  # noqa: E402

RHO, G = 1000.0, 9.81


def cut_through_the_material(sim: Simulation) -> bool:
    """Whether a box boundary crosses the material along x (always, on more than one rank:
    the bisection splits the particles)."""
    boxes = sim.scheme.boxes
    cuts = [int(c) * sim.grid.spacing for c in boxes.hi[:, 0] if c < boxes.cells[0]]
    x = whole(sim)[0].x[:, 0]
    return any(x.min() < c < x.max() for c in cuts)


def test_a_solid_column_at_rest_is_exact_across_the_rank_boundaries():
    """A Drucker-Prager column between slip walls, cut by the ranks' boxes across its
    width: at rest, its pressure hydrostatic, its deviatoric stress 0."""
    over = [
        "domain.size=[0.2, 0.15]",
        "bodies.0.max=[0.2, 0.1]",
        "time.end=0.2",
        "output.snapshots=false",
        "material.model='drucker_prager'",
        "material.friction_angle=30.0",
        "material.shear_modulus=1e4",
    ]
    sim = split(Simulation(load_case(EXAMPLES / "hydrostatic.toml", over)))
    sim.run()
    if world().size > 1:
        assert cut_through_the_material(sim)
    P = sim.particles
    exact = RHO * G * (0.1 - P.x[:, 1])
    assert np.abs(P.v).max() < 1e-9  # m/s
    assert np.abs(P.pressure - exact).max() < 1e-8 * RHO * G * 0.1
    assert np.abs(sim.history["stress"]).max() < 1e-5  # Pa


def bui(sim_of=Simulation) -> Simulation:
    case = load_case(EXAMPLES / "bui_column.toml", ["grid.spacing=0.005", "time.end=0.05"])
    return sim_of(case)


def test_a_collapsing_drucker_prager_column_over_the_ranks_is_the_one_process_run():
    """The Bui column (cohesionless Drucker-Prager, its strength the projection's pressure)
    collapsing for 50 ms, split across its width: the particles, their stress and plastic
    strain, and the cells' pressure follow one process; a checkpoint of the split run
    continues on one process as the one-process run does."""
    one = alone(bui())
    many = split(bui())
    a = one.scheme.advance(one.dt, 250)
    b = many.scheme.advance(many.dt, 250)
    if world().size > 1:
        assert cut_through_the_material(many)
    assert a.unknowns == b.unknowns  # the cells with material, each counted once
    P, hm = whole(many)
    assert np.abs(P.x - one.particles.x).max() < 1e-8  # m
    assert np.abs(P.v - one.particles.v).max() < 1e-6  # m/s
    h1 = one.history
    assert np.abs(hm["stress"] - h1["stress"]).max() < 1e-2  # Pa
    assert np.abs(h1["stress"]).max() > 100.0  # Pa: the column is loaded
    assert np.abs(hm["plastic_strain"] - h1["plastic_strain"]).max() < 1e-6
    assert h1["yielding"].sum() > 0 and np.array_equal(hm["yielding"], h1["yielding"])
    p_cell = many.scheme.state()["p_cell"]
    assert np.abs(p_cell - one.scheme.core.p_cell).max() < 1e-6 * 2040.0 * G * 0.1
    # the split run's state continues on one process
    again = alone(bui())
    again.particles.x[:] = P.x
    again.particles.v[:] = P.v
    again.particles.pressure[:] = P.pressure
    again.scheme.restore({**many.scheme.state(), **hm})
    one.scheme.advance(one.dt, 250)
    again.scheme.advance(again.dt, 250)
    assert np.abs(again.particles.x - one.particles.x).max() < 1e-8  # m
    assert np.abs(again.history["stress"] - one.history["stress"]).max() < 1e-2  # Pa


FOOTING = (
    "obstacles=[{name='footing', type='box', min=[2.0, 3.0], max=[3.0, 3.4], walls='no_slip', "
    "motion={type='velocity', velocity=[0.0, -0.1]}}]"
)


def footing(linear_solver: str) -> Simulation:
    """examples/footing.toml's clay with a whole footing (1 m wide) in the middle, where the
    ranks' first cut lies, at B / 8."""
    over = ["grid.spacing=0.125", FOOTING, f"solver.linear_solver={linear_solver}"]
    return Simulation(load_case(EXAMPLES / "footing.toml", over))


def test_a_footing_pushed_into_clay_across_the_rank_boundary_follows_one_process():
    """A solid's tool on the ranks: the halo takes its owners' new stress before the tool's
    reaction reads the stress round its nodes (tools' nodes owned by both ranks), and the
    reactions are summed over the ranks. Against one process with PETSc's solver (the core's
    multigrid leaves a different rounding, and at step 7 a wall contact whose pressure is
    0 to rounding lets go on one side only: 1.7e-6 m apart after 100 steps, on one process
    too): the clay to 1e-8 m (measured on 2 ranks: 5.6e-12 m) and the footing's force to
    1e-3 of itself (measured: 9.6e-5 at one step of 60, where a tool node's contact, its
    pressure 0 to rounding, differs; 1e-9 elsewhere; without the owners' stress, 207 N of
    49 kN)."""
    one = alone(footing("petsc"))
    many = split(footing("multigrid"))
    forces = []
    for _ in range(60):
        one.scheme.advance(one.dt, 1)
        many.scheme.advance(many.dt, 1)
        forces.append((one.scheme.body_values()[0][0, 1], many.scheme.body_values()[0][0, 1]))
    if world().size > 1:
        cuts = [int(c) * 0.125 for c in many.scheme.boxes.hi[:, 0] if c < 40]
        assert any(2.0 < c < 3.0 for c in cuts)  # under the footing
    assert np.abs(whole(many)[0].x - one.particles.x).max() < 1e-8  # m
    a, b = np.array(forces).T
    assert a.max() > 1e4  # N/m: the clay pushes the footing up
    assert np.abs(b - a).max() < 1e-3 * np.abs(a).max()
