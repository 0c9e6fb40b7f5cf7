"""Explicit weakly compressible MPM: the comparator of Kularathna & Soga (2017), section 4.

Update stress last (USL): the grid velocity after the momentum update moves the particles
and gives the volumetric strain rate, so the particles' volumes follow their motion. The
material is water with bulk modulus K: p = -K * volumetric strain = K (1 - J), J = V / V0,
once per cell from the particles in it (every particle of a cell takes the cell's J); no
tension by default (J <= 1, ``solver.explicit_tension``); a cell too empty to define a
volumetric strain holds no pressure (``solver.explicit_cell_threshold``). The cell pressure
drives the motion at the cell centre (at the particles' centroid in partly filled cells),
the transpose of the strain rate; the particles report it smoothed through the nodes
(``solver.pressure_smoothing``, output only). With time.dt = "auto" the step is
re-evaluated every step from the current speeds. The kernel is the core's explicit scheme
(src/core/explicit_scheme.hpp, reached through ``mpmflow.state``), written once for 2D and
3D, with the grid's weights and the projection scheme's wall and put-back rules. The
choices, the cures and the variants tried and rejected: docs/method.md, "The explicit
comparator"."""

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from .. import state
from ..boundaries import walls
from ..errors import SimulationError
from ..stability import sound_speed, stable_time_step
from . import register
from .projection import StepReport


@dataclass
class ExplicitReport(StepReport):
    steps: int = 0  # the steps taken (with time.dt = "auto", as many as the state needed)


@register("explicit")
class ExplicitScheme:
    # water only, walls only (the weakly compressible comparator)
    SUPPORTS: ClassVar[frozenset[str]] = frozenset()

    def __init__(self, case, grid, particles):
        self.grid = grid
        self.particles = particles
        m, sv = case.material, case.solver
        self.density = m.density
        self.bulk = m.bulk_modulus
        self.sound_speed = sound_speed(m.bulk_modulus, m.density)
        self.gravity = np.asarray(case.physics.gravity, dtype=float)
        self.no_slip = walls.side_conditions(case)  # x_min, x_max, y_min, ...
        self.flip = sv.flip
        self.smoothing = sv.pressure_smoothing == "nodal"
        self.full = sv.full_cell_threshold
        self.sparse = sv.explicit_cell_threshold
        self.mass_cut = sv.explicit_mass_cutoff
        self.q_lin, self.q_quad = (float(q) for q in sv.explicit_bulk_viscosity)
        self.tension = sv.explicit_tension
        self.max_speed = sv.max_speed
        self.auto = case.time.dt == "auto"
        self.safety = case.time.safety_factor
        self.upper = np.asarray(grid.size, dtype=float)
        n, d, c = grid.nnodes, grid.dim, grid.ncells
        self.node_mass = np.zeros(n)
        self.node_mom = np.zeros((n, d))
        self.v_old = np.zeros((n, d))
        self.v_new = np.zeros((n, d))
        self.contact = np.zeros((n, d), dtype=np.bool_)
        self.cell_j = np.zeros(c)
        self.cell_vol = np.zeros(c)
        self.cell_v0 = np.zeros(c)
        self.cell_xi = np.zeros((c, d))
        self.cell_p = np.zeros(c)
        self.cell_q = np.zeros(c)
        self.node_w = np.zeros(n)
        self.node_p = np.zeros(n)
        self.stats = np.zeros(6)
        self.smallest_dt = np.inf  # the smallest step taken so far (s)
        self.clock = np.zeros(2)  # the simulated time (s) and the steps taken so far
        self.last_unknowns = 0
        # an initial pressure is an initial compression: V = (1 - p / K) m / rho
        particles.volume[:] = (1.0 - particles.pressure / self.bulk) * particles.mass / self.density
        self._pressure()

    def _pressure(self):
        g, P = self.grid, self.particles
        state.explicit_cell_state(
            g,
            P.x,
            P.mass,
            P.volume,
            self.density,
            self.bulk,
            self.tension,
            self.full,
            self.sparse,
            self.cell_j,
            self.cell_vol,
            self.cell_v0,
            self.cell_xi,
            self.cell_p,
        )
        state.explicit_particle_state(
            g,
            P.x,
            P.mass,
            P.volume,
            P.pressure,
            self.density,
            self.smoothing,
            self.cell_j,
            self.cell_vol,
            self.cell_p,
            self.node_w,
            self.node_p,
        )

    _STATE = ("cell_j", "cell_vol", "cell_v0", "cell_xi", "cell_p", "clock", "smallest")

    @property
    def smallest(self):
        return np.array([self.smallest_dt])

    def state(self):
        """What the scheme carries from one step to the next beyond the particles (whose
        volume is their compression J): the cell state the next step starts from, and the
        smallest step and the clock. The cell state is not recomputed from the particles on a
        restart because that would not be bit-identical (the particles' volumes are set from
        their cell's J after the sums were taken)."""
        return {name: np.array(getattr(self, name), copy=True) for name in self._STATE}

    def restore(self, saved):
        """Continue from ``state()`` (a checkpoint)."""
        for name in self._STATE[:-1]:
            np.copyto(getattr(self, name), saved[name])
        self.smallest_dt = float(saved["smallest"][0])

    def stable_time_step(self):
        """h / (c + |v|max) at the current particle speeds (s)."""
        speed = float(state.explicit_max_speed(self.particles.v))
        return stable_time_step(self.grid.spacing, self.bulk, self.density, speed)

    def advance(self, dt, nsteps, where=lambda k: ""):
        """The span nsteps * dt in one compiled call; ``where(k)`` names step k in messages.
        With time.dt = "auto" the span is cut into steps re-evaluated every step from the
        current speeds (``state.explicit_steps``), as many as needed; else nsteps
        steps of dt, whose stability is checked once, after the last step."""
        g, P = self.grid, self.particles
        state.explicit_steps(
            g,
            nsteps * dt,
            nsteps,
            self.safety if self.auto else 0.0,
            P.x,
            P.v,
            P.pressure,
            P.mass,
            P.volume,
            self.density,
            self.bulk,
            self.gravity,
            self.flip,
            self.no_slip,
            self.smoothing,
            self.full,
            self.sparse,
            self.mass_cut,
            self.q_lin,
            self.q_quad,
            self.tension,
            self.max_speed,
            self.upper,
            1e-6 * g.spacing,
            self.node_mass,
            self.node_mom,
            self.v_old,
            self.v_new,
            self.contact,
            self.cell_j,
            self.cell_vol,
            self.cell_v0,
            self.cell_xi,
            self.cell_p,
            self.cell_q,
            self.node_w,
            self.node_p,
            self.stats,
        )
        steps, _, smallest, moved, stopped, vmax = self.stats
        steps = int(steps)
        self.smallest_dt = min(self.smallest_dt, smallest)
        self.clock += (self.stats[1], steps)
        if stopped:
            fastest = int(np.argmax(np.sum(P.v**2, axis=1)))
            xy = ", ".join(f"{c:.4g}" for c in P.x[fastest])
            step = "time.safety_factor" if self.auto else "time.dt"
            raise SimulationError(
                f"The run blew up at step {int(self.clock[1])} (t = {self.clock[0]:.6g} s, "
                f"explicit scheme): particle {fastest} at ({xy}) m moves at {vmax:.4g} m/s, "
                f"above solver.max_speed = {self.max_speed:g} m/s. The outputs written so far "
                f"are kept. Try a smaller {step}, a larger solver.explicit_cell_threshold "
                f"(now {self.sparse:g}) or solver.explicit_bulk_viscosity (now "
                f"[{self.q_lin:g}, {self.q_quad:g}]), or raise solver.max_speed if such "
                "speeds are real."
            )
        if not self.auto:
            limit = self.stable_time_step()
            if not dt <= limit:  # also catches NaN speeds
                raise SimulationError(
                    f"The explicit step became unstable{where(nsteps - 1)} (checked once per "
                    f"output interval): the flow reached {vmax:.3g} m/s, so the stable step "
                    f"grid.spacing / (sound speed {self.sound_speed:.4g} m/s + flow speed) is "
                    f"{limit:.3g} s, below time.dt = {dt:.3g} s. Use a smaller time.dt, or "
                    'time.dt = "auto", which re-evaluates the step every step.'
                )
        return ExplicitReport(moved_inside=int(moved), steps=steps)
