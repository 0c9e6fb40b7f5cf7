"""Volume correction: particles moved, never accelerated, back to the material's volume.

The projection makes the grid velocity divergence-free only approximately, and particles
drift: they pack in places and thin out in others, and the water's volume as the particles
occupy it drifts with them. Each step this module measures the particles' volume fraction on
the cell-centred grid and computes a displacement of the particles, not of their velocity,
that brings it back to 1 (after Kugelstadt et al. 2021, "Implicit density projection for
volume conserving liquids"):

1. density: rho_c = sum_p N_c(x_p) V_p / h^d with the bilinear hat of the cell-centred grid,
   particles mirrored at walls (``kernels.volume2d.scatter_cell_volume``, summed by the
   particle-to-grid kernel in the same pass); smooth, and exact for
   a lattice of particles however it is shifted or strained (a per-cell count is not: a row of
   particles crossing a cell edge changes it by 1/4);
2. a Poisson system on the cells holding material, -lap q = rho - 1, with q = 0 in empty
   cells and no flux through walls. Near the free surface (a cell within one cell of a cell
   less than half full) the density reads low because part of its kernel lies in air, so only
   an excess counts there: the surface is never pulled inward by its own thinness, and the
   interior's gaps are closed by drawing the surface down;
3. the displacement d = -beta h grad q on the cell faces (0 on walls, so nothing is pushed
   into a wall), interpolated to each particle from its own faces and added to the particle's
   position in the grid-to-particle step (``kernels.transfer2d``).

It removes the fraction beta of the volume error each step, both ways: packed cells spread
out and loosened regions close up. Velocities are untouched, so the correction puts no
kinetic energy into the flow (the density correction of the pressure equation, which asks for
div v = beta (vol/V - 1)/dt, does: under FLIP the velocity it adds is kept). Measured choices
and the candidates that lost: docs/method.md.
"""

import numpy as np

from .errors import SolverError
from .kernels import multigrid, volume2d

TOLERANCE = 1e-2  # relative residual of the solve: a correction, not a constraint (measured: 1e-4 and 1e-1 give the same runs)
MAX_ITERATIONS = 200
MAX_DISPLACEMENT = 0.5  # cells per step, a safety bound (Kugelstadt et al.)
WET = 0.5  # a cell less than half full is surface, as for the front, height and wetted volume


class VolumeCorrection:
    """``faces(cell_vol, theta, contact)`` once per step, after the pressure step (whose wall
    contact tells where the material has left a wall), gives the face displacements (m) that
    ``grid_to_particles`` adds to the particles' positions. ``state``/``restore``: the last
    solution, the warm start of the next solve (checkpoints carry it)."""

    def __init__(self, grid, rate):
        if grid.dim != 2:
            raise NotImplementedError("only 2D grids are implemented")
        self.grid = grid
        self.rate = rate  # beta: fraction of the volume error removed per step
        nx, ny = grid.cells
        n = grid.ncells
        self.cell_vol = np.zeros(n)  # sum_p N_c V_p at the cell centres, from particles_to_grid
        self.density = np.zeros(n)
        self._row = np.empty(n, dtype=np.int64)
        self._cells = np.empty(n, dtype=np.int64)
        self._cols = np.empty((n, 9), dtype=np.int64)
        self._vals = np.empty((n, 9))
        self._rhs = np.empty(n)
        self._q = np.zeros(n)  # last solution per cell: the next solve's warm start
        self.dx_face = np.zeros((nx + 1) * ny)
        self.dy_face = np.zeros(nx * (ny + 1))
        self.iterations = 0

    def faces(self, cell_vol, theta, contact, where=""):
        """``cell_vol``: the particles' volume on the cell centres (``particles_to_grid``
        computes it into ``self.cell_vol``), ``theta``: the cell volume fractions."""
        g = self.grid
        nx, ny = g.cells
        np.multiply(cell_vol, 1.0 / g.cell_volume, out=self.density)
        n, anchored = volume2d.assemble_2d(nx, ny, theta, self.density, WET, contact,
                                           self._row, self._cols, self._vals, self._rhs,
                                           self._cells)
        if n == 0 or not anchored:
            # nothing, or material filling the whole domain: its volume cannot change
            self.dx_face[:] = 0.0
            self.dy_face[:] = 0.0
            self.iterations = 0
            return self.dx_face, self.dy_face
        cells = self._cells[:n]
        rhs = self._rhs[:n]
        q = self._q[cells]
        setup = multigrid.build_hierarchy(self._cols[:n], self._vals[:n], cells,
                                          np.array(g.cells, dtype=np.int64), multigrid.COARSEST)
        iterations, residual = multigrid.pcg(*setup, rhs, q, TOLERANCE, MAX_ITERATIONS, 1)
        if not residual <= TOLERANCE:
            raise SolverError(
                f"The volume correction's solve did not converge{where}: relative residual "
                f"{residual:.3e} after {iterations} iterations on {n} cells. Try a smaller "
                "time.dt, or switch the correction off with solver.volume_correction = 0.")
        self.iterations = int(iterations)
        self._q[:] = 0.0
        self._q[cells] = q
        volume2d.face_displacements_2d(nx, ny, self._row, q, self.rate * g.spacing,
                                       MAX_DISPLACEMENT * g.spacing, self.dx_face, self.dy_face)
        return self.dx_face, self.dy_face

    def state(self):
        return self._q.copy()

    def restore(self, q):
        np.copyto(self._q, q)
