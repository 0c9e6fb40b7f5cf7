"""The pressure step of the projection (docs/method.md, steps 5 and 6): assemble eq. (13),
solve it with the walls as contact conditions, extend the pressure to ghost nodes, and
correct the grid velocity (eq. 16)."""

from dataclasses import dataclass

import numpy as np

from .boundaries import apply_walls
from .errors import SolverError
from .kernels import pressure2d, walls2d
from .linsolve import LinearSolver, PressureMatrix


@dataclass
class PressureStats:
    unknowns: int = 0
    iterations: int = 0
    residual: float = 0.0
    solves: int = 0
    released: int = 0


class PressureProjection:
    """Owns the nodal pressure and the linear solver; ``project`` once per time step."""

    def __init__(self, grid, density, walls, wall_flux, theta_min, density_correction, method,
                 tolerance, max_iterations):
        if grid.dim != 2:
            raise NotImplementedError("only 2D grids are implemented")
        self.grid = grid
        self.density = density
        self.walls = walls
        self.wall_flux = wall_flux
        self.theta_min = theta_min
        self.density_correction = density_correction
        self.solver = LinearSolver(method, tolerance, max_iterations)
        self.p_node = np.zeros(grid.nnodes)  # this step's nodal pressure (Pa)
        self._p_next = np.zeros(grid.nnodes)
        self._rhs = np.empty(0)
        self._v_c = np.zeros((grid.nnodes, grid.dim))

    def _matrix(self, integrals, nodes, where):
        nx, ny = self.grid.cells
        n = nodes.nrows
        cols = np.empty((n, 9), dtype=np.int64)
        vals = np.empty((n, 9))
        anchored = np.empty(n, dtype=np.bool_)
        pressure2d.assemble_matrix_2d(nx, ny, integrals.slot, integrals.K, nodes.row, nodes.f,
                                      nodes.subcell, self.theta_min, cols, vals, anchored)
        if not anchored.any():
            raise SolverError(
                f"The pressure system is singular{where}: the material touches no free surface "
                "(it fills a closed container), so the pressure is defined only up to a "
                "constant. mpmflow needs a free surface; leave some empty space in the domain.")
        return PressureMatrix(cols, vals, nodes.row_nodes(), self.grid.nodes)

    def project(self, integrals, nodes, node_vol, vstar, contact, dt, v_new, where=""):
        """Solve for p^{t+1} (kept in ``p_node``) and write v^{t+1} into ``v_new``.

        ``contact`` (modified) starts with all wall nodes that carry a pressure unknown, and
        the others where v* presses into the wall, holding the material; a wall node whose
        pressure comes out negative while v* leaves the wall is released and the pressure is
        solved again (the matrix and its preconditioner are kept).
        """
        g = self.grid
        nx, ny = g.cells
        n = nodes.nrows
        rho = self.density
        stats = PressureStats(unknowns=n)
        p_node = self._p_next
        p_node[:] = 0.0
        # wall nodes without a pressure of their own (at the free surface, p ~ 0) hold the
        # material only while it presses into the wall
        walls2d.start_contact_2d(nx, ny, vstar, nodes.row, contact)
        if n:
            matrix = self._matrix(integrals, nodes, where)
            try:
                self.solver.prepare(matrix)
            except (np.linalg.LinAlgError, RuntimeError, ValueError) as err:
                raise SolverError(f"The pressure solver could not be set up{where}: {err}. "
                                  f"{n} unknowns. Try solver.linear_solver = \"direct\" or "
                                  "a smaller time.dt.") from None
            rows = matrix.nodes
            x0 = self.p_node[rows]
            rhs = self._rhs if self._rhs.size >= n else np.empty(2 * n)
            self._rhs = rhs
            rhs = rhs[:n]
            while True:
                v_c = vstar
                if not self.wall_flux:  # the paper: divergence of the wall-constrained v*
                    v_c = self._v_c
                    np.copyto(v_c, vstar)
                    apply_walls(g, v_c, contact, self.walls)
                div_slot, C_div, V_cells = integrals.divergence()
                pressure2d.assemble_rhs_2d(nx, ny, g.spacing, div_slot, C_div, V_cells, node_vol,
                                           rows, v_c, contact,
                                           self.wall_flux, self.density_correction / dt,
                                           rho / dt, rhs)
                result = self.solver.solve(rhs, x0)
                stats.solves += 1
                stats.iterations += result.iterations
                stats.residual = max(stats.residual, result.residual)
                if not result.converged:
                    self._fail(rhs, result, rows, where)
                x0 = result.x
                p_node[rows] = result.x
                released = walls2d.release_contact_2d(nx, ny, vstar, nodes.row, p_node, contact)
                if not released:
                    break
                stats.released += released
            if nodes.subcell:
                pressure2d.ghost_pressures_2d(nx, ny, integrals.slot, integrals.K, nodes.row,
                                              nodes.f, self.theta_min, p_node)
        self._p_next, self.p_node = self.p_node, p_node
        slot, C, V = integrals.corrector()
        pressure2d.correct_velocity_2d(nx, ny, slot, C, V, p_node, vstar, dt / rho, v_new)
        return stats

    def _fail(self, rhs, result, rows, where):
        worst = int(np.nanargmax(np.abs(self.solver.residual_vector(rhs, result.x))))
        xy = self.grid.node_coordinates()[rows[worst]]
        raise SolverError(
            f"The pressure solve did not converge{where}: relative residual "
            f"{result.residual:.3e} after {result.iterations} iterations (solver.tolerance = "
            f"{self.solver.tolerance:g}, solver.max_iterations = {self.solver.max_iterations}); "
            f"{rows.size} unknowns, largest residual at node "
            f"({', '.join(f'{c:.4g}' for c in xy)}) m. Try solver.linear_solver = \"direct\", "
            "a smaller time.dt, or a larger solver.max_iterations.")
