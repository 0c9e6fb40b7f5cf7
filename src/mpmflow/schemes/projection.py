"""Chorin's projection in MPM (Kularathna & Soga 2017; one time step as in docs/method.md)."""

from dataclasses import dataclass

import numpy as np

from .. import transfers
from ..boundaries import apply_walls
from ..cells import bin_particles
from ..free_surface import FreeSurface
from ..pressure import PressureProjection
from ..quadrature import Quadrature
from ..volume_correction import VolumeCorrection
from . import register


@dataclass
class StepReport:
    """What a scheme reports after one or more steps."""

    unknowns: int = 0  # the largest count of pressure unknowns in a step
    solves: int = 0
    iterations: int = 0
    max_iterations: int = 0  # the most iterations in one step
    residual: float = 0.0  # the worst relative residual
    released: int = 0
    moved_inside: int = 0

    def merge(self, other):
        return StepReport(max(self.unknowns, other.unknowns), self.solves + other.solves,
                          self.iterations + other.iterations,
                          max(self.max_iterations, other.max_iterations),
                          max(self.residual, other.residual), self.released + other.released,
                          self.moved_inside + other.moved_inside)


@register("projection")
class ProjectionScheme:
    def __init__(self, case, grid, particles):
        s = case.solver
        self.grid = grid
        self.particles = particles
        self.gravity = np.asarray(case.physics.gravity, dtype=float)
        self.walls = case.domain.walls
        self.flip = s.flip
        self.quadrature = Quadrature(grid, s.full_cell_threshold, s.sparse_cell_threshold,
                                     s.partial_cell_quadrature, s.surface_quadrature)
        self.surface = FreeSurface(grid, s.free_surface)
        self.projection = PressureProjection(grid, case.material.density, case.domain.walls,
                                             s.wall_flux, s.ghost_theta_min,
                                             s.density_correction, s.linear_solver,
                                             s.tolerance, s.max_iterations)
        self.volume = (VolumeCorrection(grid, s.volume_correction) if s.volume_correction > 0
                       else None)
        self.volume_interval = s.volume_correction_interval  # s
        self.steps = 0  # steps taken: the volume correction runs on every n-th (n from dt)
        self.contact = np.zeros((grid.nnodes, grid.dim), dtype=np.bool_)
        n, d = grid.nnodes, grid.dim
        self.node_mass = np.zeros(n)
        self.node_mom = np.zeros((n, d))
        self.node_vol = np.zeros(n)
        self.v_old = np.zeros((n, d))
        self.v_star = np.zeros((n, d))
        self.v_new = np.zeros((n, d))
        self.bins = None
        self.last_unknowns = 0

    def state(self):
        """What the scheme carries from one step to the next beyond the particles: the nodal
        pressure and the volume correction's last solution (the warm starts of the next
        solves). Everything else is rebuilt each step."""
        state = {"p_node": self.projection.p_node.copy(),
                 "last_unknowns": np.array(self.last_unknowns), "steps": np.array(self.steps)}
        if self.volume is not None:
            state["volume_q"] = self.volume.state()
        return state

    def restore(self, state):
        """Continue from ``state()`` (a checkpoint)."""
        self.projection.p_node = state["p_node"].copy()
        self.last_unknowns = int(state["last_unknowns"])
        self.steps = int(state["steps"])
        if self.volume is not None:
            self.volume.restore(state["volume_q"])

    def check_free_surface(self):
        """Raise SolverError ("singular") when the material as placed touches no free
        surface: the first step's classification and assembly, without the solve (its
        buffers are overwritten by the step). Lets a run refuse such a case before it
        starts instead of failing at step 1."""
        g, P = self.grid, self.particles
        bins = bin_particles(g, P)
        node_f = self.surface.nodal_fraction(bins.theta)
        integrals = self.quadrature.integrals(P, bins, self.surface.enclosed_cells(node_f))
        nodes = self.surface.classify(integrals, node_f)
        if nodes.nrows:
            self.projection._matrix(integrals, nodes, " at the start")

    def advance(self, dt, nsteps, where=""):
        """``nsteps`` steps of size dt; ``where(k)`` names step k in messages. The report sums
        the steps (residual: the worst)."""
        total = StepReport()
        for k in range(nsteps):
            total = total.merge(self.step(dt, where=where(k)))
        return total

    def step(self, dt, where=""):
        g, P = self.grid, self.particles
        self.steps += 1
        every = max(1, round(self.volume_interval / dt))  # steps
        correct = self.volume is not None and self.steps % every == 0
        # 1-2. particle-to-grid and the predictor with gravity (eqs. 10-12); wall conditions
        # are applied in step 5
        self.bins = bin_particles(g, P, self.bins)
        transfers.particles_to_grid(g, P, self.bins, self.gravity, dt, self.node_mass,
                                    self.node_mom, self.node_vol, self.v_old, self.v_star,
                                    self.volume.cell_vol if correct else None)
        # 3. cell classification and quadrature (eqs. 8, 9)
        node_f = self.surface.nodal_fraction(self.bins.theta)
        integrals = self.quadrature.integrals(P, self.bins, self.surface.enclosed_cells(node_f))
        # 4. free surface
        nodes = self.surface.classify(integrals, node_f)
        # 5-6. pressure Poisson equation with contact walls, and corrector (eqs. 13-18)
        stats = self.projection.project(integrals, nodes, self.node_vol, self.v_star,
                                        self.contact, dt, self.v_new, where)
        apply_walls(g, self.v_new, self.contact, self.walls)
        # 7. volume correction: a displacement of the particles back to the material's volume
        faces = (self.volume.faces(self.volume.cell_vol, self.bins.theta, self.contact, where)
                 if correct else None)
        # 8. grid-to-particle (eqs. 19-21), the correction's displacement, pressure to particles
        moved = transfers.grid_to_particles(g, P, self.v_old, self.v_new,
                                            self.projection.p_node, dt,
                                            transfers.flip_per_step(self.flip, dt), faces)
        self.last_unknowns = stats.unknowns
        return StepReport(stats.unknowns, stats.solves, stats.iterations, stats.iterations,
                          stats.residual, stats.released, moved)
