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

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np
from numpy.typing import NDArray

from .. import state
from ..boundaries import inlets, outlets, walls
from ..case import capabilities
from ..errors import SimulationError
from ..grid import Grid
from ..particles import Particles
from ..stability import sound_speed, stable_time_step
from .projection import StepReport, preset

if TYPE_CHECKING:  # the case asks the scheme registry what each scheme supports
    from ..case import Case


@dataclass
class ExplicitReport(StepReport):
    steps: int = 0  # the steps taken (with time.dt = "auto", as many as the state needed)


class ExplicitScheme:
    # water only, walls only (the weakly compressible comparator)
    SUPPORTS: ClassVar[frozenset[str]] = capabilities.SUPPORTS["explicit"]

    def __init__(self, case: Case, grid: Grid, particles: Particles) -> None:
        self.grid = grid
        self.particles = particles
        self.outflow = outlets.Outflow()  # no outlets: nothing leaves
        self.inflow = inlets.Inflow()  # no inlets: nothing enters
        m, sv = case.material, case.solver
        q_lin, q_quad = (float(q) for q in sv.explicit_bulk_viscosity)
        self.settings = state.ExplicitSettings(
            density=m.density,
            bulk=m.bulk_modulus,
            gravity=np.asarray(case.physics.gravity, dtype=float),
            flip=preset(sv.flip, "flip"),
            no_slip=walls.side_conditions(case),  # x_min, x_max, y_min, ...
            smoothing=sv.pressure_smoothing == "nodal",
            full=sv.full_cell_threshold,
            sparse=sv.explicit_cell_threshold,
            mass_cut=sv.explicit_mass_cutoff,
            q_lin=q_lin,
            q_quad=q_quad,
            tension=sv.explicit_tension,
            max_speed=sv.max_speed,
        )
        self.sound_speed = sound_speed(m.bulk_modulus, m.density)
        self.auto = case.time.dt == "auto"
        self.safety = case.time.safety_factor
        self.work = state.ExplicitWork.zeros(grid)
        self.smallest_dt = np.inf  # the smallest step taken so far (s)
        self.clock = np.zeros(2)  # the simulated time (s) and the steps taken so far
        self.last_unknowns = 0
        # an initial pressure is an initial compression: V = (1 - p / K) m / rho
        s = self.settings
        particles.volume[:] = (1.0 - particles.pressure / s.bulk) * particles.mass / s.density
        self._pressure()

    def _pressure(self) -> None:
        state.explicit_cell_state(self.grid, self.particles, self.settings, self.work)
        state.explicit_particle_state(self.grid, self.particles, self.settings, self.work)

    _CELLS = ("cell_j", "cell_vol", "cell_v0", "cell_xi", "cell_p")  # in ``work``

    def state(self) -> dict[str, NDArray[Any]]:
        """What the scheme carries from one step to the next beyond the particles (whose
        volume is their compression J): the cell state the next step starts from, and the
        smallest step and the clock. The cell state is not recomputed from the particles on a
        restart because that would not be bit-identical (the particles' volumes are set from
        their cell's J after the sums were taken)."""
        saved = {name: np.array(getattr(self.work, name), copy=True) for name in self._CELLS}
        return {**saved, "clock": self.clock.copy(), "smallest": np.array([self.smallest_dt])}

    def restore(self, saved: dict[str, NDArray[Any]]) -> None:
        """Continue from ``state()`` (a checkpoint)."""
        for name in self._CELLS:
            np.copyto(getattr(self.work, name), saved[name])
        np.copyto(self.clock, saved["clock"])
        self.smallest_dt = float(saved["smallest"][0])

    def stable_time_step(self) -> float:
        """h / (c + |v|max) at the current particle speeds (s)."""
        speed = float(state.explicit_max_speed(self.particles.v))
        s = self.settings
        return stable_time_step(self.grid.spacing, s.bulk, s.density, speed)

    def advance(
        self, dt: float, nsteps: int, where: Callable[[int], str] = lambda k: ""
    ) -> ExplicitReport:
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
            P,
            self.settings,
            self.work,
            1e-6 * g.spacing,
        )
        stats = self.work.stats
        steps, _, smallest, moved, stopped, vmax = stats
        steps = int(steps)
        self.smallest_dt = min(self.smallest_dt, smallest)
        self.clock += (stats[1], steps)
        if stopped:
            fastest = int(np.argmax(np.sum(P.v**2, axis=1)))
            xy = ", ".join(f"{c:.4g}" for c in P.x[fastest])
            step = "time.safety_factor" if self.auto else "time.dt"
            raise SimulationError(
                f"The run blew up at step {int(self.clock[1])} (t = {self.clock[0]:.6g} s, "
                f"explicit scheme): particle {fastest} at ({xy}) m moves at {vmax:.4g} m/s, "
                f"above solver.max_speed = {self.settings.max_speed:g} m/s. The outputs written so far "
                f"are kept. Try a smaller {step}, a larger solver.explicit_cell_threshold "
                f"(now {self.settings.sparse:g}) or solver.explicit_bulk_viscosity (now "
                f"[{self.settings.q_lin:g}, {self.settings.q_quad:g}]), or raise solver.max_speed if such "
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
