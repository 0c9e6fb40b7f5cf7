"""Volume correction: particles moved, never accelerated, back to the material's volume.

The projection makes the grid velocity divergence-free only approximately, and particles
drift: they pack in places and thin out in others, and the water's volume as the particles
occupy it drifts with them. Each step this module measures the particles' volume fraction on
the cell-centred grid and computes a displacement of the particles, not of their velocity,
that brings it back to 1 (after Kugelstadt et al. 2021, "Implicit density projection for
volume conserving liquids"):

1. density: rho_c = sum_p N_c(x_p) V_p / h^d with the bilinear hat of the cell-centred grid,
   particles mirrored at walls (src/core/transfer.hpp's ``scatter_cell_volume``, summed by the
   particle-to-grid kernel in the same pass); smooth, and exact for
   a lattice of particles however it is shifted or strained (a per-cell count is not: a row of
   particles crossing a cell edge changes it by 1/4);
2. a Poisson system on the cells holding material, -lap q = rho - 1, with q = 0 in empty
   cells and no flux through walls. Near the free surface (a cell within one cell of a cell
   less than half full) the density reads low because part of its kernel lies in air, so only
   an excess counts there: the surface is never pulled inward by its own thinness, and the
   interior's gaps are closed by drawing the surface down. It is solved to
   ``solver.volume_correction_tolerance``, by default the pressure's 1e-8: at 1e-2 the run
   depended on the solver (one process moved the 2D dam break's front by 0.0026 a between
   1e-2 and 1e-4, and a run over MPI ranks, solved by PETSc, the 3D column's height by a
   cell), at 1e-8 it does not, for about three more multigrid iterations a step in 2D
   (docs/notes/benchmarks-diary.md; in 3D at 0.004 m, 24 a correction against 15 at 1e-4);
3. the displacement d = -beta h grad q on the cell faces (0 on walls, so nothing is pushed
   into a wall), interpolated to each particle from its own faces and added to the particle's
   position in the grid-to-particle step (src/core/transfer).

It removes the fraction beta of the volume error each step, both ways: packed cells spread
out and loosened regions close up. Velocities are untouched, so the correction puts no
kinetic energy into the flow (the density correction of the pressure equation, which asks for
div v = beta (vol/V - 1)/dt, does: under FLIP the velocity it adds is kept). Measured choices
and the candidates that lost: docs/method.md.

The compiled step runs it (``State::volume_correction`` in src/core/step.cpp, on the
kernels of src/core/volume_correction); this module holds its constants and its failure message.
"""

from ..errors import SolverError

MAX_ITERATIONS = 200
MAX_DISPLACEMENT = 0.5  # cells per step, a safety bound (Kugelstadt et al.)


def not_converged(where: str, residual: float, iterations: int, cells: int) -> SolverError:
    return SolverError(
        f"The volume correction's solve did not converge{where}: relative residual "
        f"{residual:.3e} after {iterations} iterations on {cells} cells "
        "(solver.volume_correction_tolerance). Try a smaller time.dt, a looser "
        "solver.volume_correction_tolerance, or switch the correction off with "
        "solver.volume_correction = 0."
    )
