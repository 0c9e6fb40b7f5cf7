"""Explicit weakly compressible MPM: the comparator of Kularathna & Soga (2017), section 4.

Update stress last (USL): the grid velocity after the momentum update moves the particles
and gives the volumetric strain rate, so the particles' volumes follow their motion. The
material is water with bulk modulus K: p = -K * volumetric strain = K (1 - J), J = V / V0,
once per cell from the particles in it (every particle of a cell takes the cell's J); no
tension (J <= 1). The cell pressure drives the motion at the cell centre (at the particles'
centroid in partly filled cells), the transpose of the strain rate; the particles report it
smoothed through the nodes (``solver.pressure_smoothing``). The kernel is
``kernels.explicit2d``; walls, FLIP/PIC and outputs are those of the projection scheme.
The choices and the variants tried and rejected: docs/method.md, "The explicit comparator".
"""

import numpy as np

from ..errors import SimulationError
from ..kernels import explicit2d
from ..stability import sound_speed, stable_time_step
from ..transfers import flip_per_step
from . import register
from .projection import StepReport


@register("explicit")
class ExplicitScheme:
    def __init__(self, case, grid, particles):
        if grid.dim != 2:
            raise NotImplementedError("only 2D grids are implemented")
        self.grid = grid
        self.particles = particles
        m = case.material
        self.density = m.density
        self.bulk = m.bulk_modulus
        self.sound_speed = sound_speed(m.bulk_modulus, m.density)
        self.gravity = np.asarray(case.physics.gravity, dtype=float)
        self.no_slip = case.domain.walls == "no_slip"
        self.flip = case.solver.flip
        self.smoothing = case.solver.pressure_smoothing == "nodal"
        self.upper = np.asarray(grid.size, dtype=float)
        n, d, c = grid.nnodes, grid.dim, grid.ncells
        self.node_mass = np.zeros(n)
        self.node_mom = np.zeros((n, d))
        self.v_old = np.zeros((n, d))
        self.v_new = np.zeros((n, d))
        self.contact = np.zeros((n, d), dtype=np.bool_)
        self.cell_j = np.zeros(c)
        self.cell_vol = np.zeros(c)
        self.cell_xi = np.zeros((c, d))
        self.full = case.solver.full_cell_threshold
        self.cell_p = np.zeros(c)
        self.node_w = np.zeros(n)
        self.node_p = np.zeros(n)
        self.last_unknowns = 0
        # an initial pressure is an initial compression: V = (1 - p / K) m / rho
        particles.volume[:] = (1.0 - particles.pressure / self.bulk) * particles.mass / self.density
        self._pressure()

    def _pressure(self):
        g, P = self.grid, self.particles
        nx, ny = g.cells
        explicit2d.cell_state_2d(P.x, P.mass, P.volume, self.density, self.bulk, g.spacing,
                                 nx, ny, self.full, self.cell_j, self.cell_vol, self.cell_xi,
                                 self.cell_p)
        explicit2d.particle_state_2d(P.x, P.mass, P.volume, P.pressure, self.density,
                                     g.spacing, nx, ny, self.smoothing, self.cell_j,
                                     self.cell_vol, self.cell_p, self.node_w, self.node_p)

    _STATE = ("cell_j", "cell_vol", "cell_xi", "cell_p")

    def state(self):
        """What the scheme carries from one step to the next beyond the particles (whose
        volume is their compression J): the cell state the next step starts from. It is not
        recomputed from the particles on a restart because that would not be bit-identical
        (the particles' volumes are set from their cell's J after the sums were taken)."""
        return {name: getattr(self, name).copy() for name in self._STATE}

    def restore(self, state):
        """Continue from ``state()`` (a checkpoint)."""
        for name in self._STATE:
            np.copyto(getattr(self, name), state[name])

    def stable_time_step(self):
        """h / (c + |v|max) at the current particle speeds (s)."""
        speed = float(np.sqrt(np.max(np.sum(self.particles.v**2, axis=1))))
        return stable_time_step(self.grid.spacing, self.bulk, self.density, speed)

    def advance(self, dt, nsteps, where=lambda k: ""):
        """``nsteps`` steps of size dt in one compiled call; ``where(k)`` names step k in
        messages. The step's stability is checked once, after the last step."""
        g, P = self.grid, self.particles
        nx, ny = g.cells
        moved = explicit2d.explicit_steps_2d(
            nsteps, dt, P.x, P.v, P.pressure, P.mass, P.volume, self.density, self.bulk,
            self.gravity[0], self.gravity[1], g.spacing, nx, ny, flip_per_step(self.flip, dt),
            self.no_slip, self.smoothing, self.full, self.upper, 1e-6 * g.spacing,
            self.node_mass, self.node_mom, self.v_old, self.v_new, self.contact, self.cell_j,
            self.cell_vol, self.cell_xi, self.cell_p, self.node_w, self.node_p)
        limit = self.stable_time_step()
        if not dt <= limit:  # also catches NaN speeds
            raise SimulationError(
                f"The explicit step became unstable{where(nsteps - 1)} (checked once per output "
                f"interval): the flow reached "
                f"{np.sqrt(np.max(np.sum(P.v**2, axis=1))):.3g} m/s, so the stable step "
                f"grid.spacing / (sound speed {self.sound_speed:.4g} m/s + flow speed) is "
                f"{limit:.3g} s, below time.dt = {dt:.3g} s. Use a smaller time.dt or "
                "time.safety_factor.")
        return StepReport(moved_inside=int(moved))
