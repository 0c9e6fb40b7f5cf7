"""Chorin's projection in MPM (Kularathna & Soga 2017; one time step as in docs/method.md).

The step itself is compiled (the core's ``State``, src/core/step.hpp, reached through
``mpmflow.state``): this class builds that state, runs chunks of steps, and turns a failure
reported by the compiled code into a message.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, ClassVar, NoReturn, TypedDict, TypeVar

import numpy as np
from numpy.typing import NDArray
from typing_extensions import Self

from .. import materials, state
from ..arrays import Floats
from ..boundaries import inlets, loads, moving, obstacles, outlets, sponges, walls
from ..case import capabilities
from ..case.domain import SIDE_NAMES
from ..errors import CaseError, SimulationError, SolverError
from ..grid import Grid
from ..linalg.solvers import SMOOTHING_SWEEPS
from ..materials import poroelastic
from ..particles import Particles
from ..stability import longest_projection_step, shallow_nodes
from ..state import CoreOptions, CoreReport
from . import pressure, volume_correction

if TYPE_CHECKING:  # the case asks the scheme registry what each scheme supports
    from ..case import Case

# the particles' arrays as the compiled step takes them: x, v, mass, volume, pressure
ParticleArrays = tuple[Floats, Floats, Floats, Floats, Floats]

MARGIN = 1e-6  # particles put back inside stay this fraction of a cell off the wall
MODEL_PARAMETERS = 8  # the material parameters the compiled step takes (zero-padded)

_T = TypeVar("_T")


def preset(value: _T | None, key: str) -> _T:
    """The value of a [solver] key that the formulation presets: typed optional because
    the preset fills it during validation, which refuses None (``case.solver``)."""
    if value is None:
        raise CaseError(f"solver.{key} is None: the case was not validated")
    return value


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
    viscous_iterations: int = 0  # of the viscous solves (viscous materials)
    capped: int = 0  # cell-steps with the viscosity held at material.max_viscosity
    clamped: int = 0  # face-steps with the volume correction's displacement clamped
    pockets: int = 0  # pocket-steps: water sealed from the free surface held at 0 at its top
    unsettled: int = 0  # steps whose walls' contact had not settled (complementarity.hpp)
    # the coupled step's plastic iterations, each one more coupled solve (State::plastic_solve)
    plastic_iterations: int = 0

    def merge(self, other: StepReport) -> StepReport:
        return StepReport(
            max(self.unknowns, other.unknowns),
            self.solves + other.solves,
            self.iterations + other.iterations,
            max(self.max_iterations, other.max_iterations),
            max(self.residual, other.residual),
            self.released + other.released,
            self.moved_inside + other.moved_inside,
            self.viscous_iterations + other.viscous_iterations,
            self.capped + other.capped,
            self.clamped + other.clamped,
            self.pockets + other.pockets,
            self.unsettled + other.unsettled,
            self.plastic_iterations + other.plastic_iterations,
        )

    @classmethod
    def of(cls, r: CoreReport) -> Self:
        """From the compiled step's ``Report``."""
        return cls(
            int(r.unknowns),
            int(r.solves),
            int(r.iterations),
            int(r.max_iterations),
            float(r.residual),
            int(r.released),
            int(r.moved),
            int(r.viscous_iterations),
            int(r.capped),
            int(r.clamped),
            int(r.pockets),
            int(r.unsettled),
            int(r.plastic_iterations),
        )


@dataclass
class AdaptiveReport(StepReport):
    """With time.dt = "auto": also the steps taken and the shortest and longest."""

    steps: int = 0
    dt_min: float = 0.0
    dt_max: float = 0.0


def most_steps(
    span: float, max_speed: float, courant: float, h: float, dt_max: float = np.inf
) -> int:
    """The most adaptive steps a span (s) can need: every particle at solver.max_speed (m/s;
    the run stops beyond it) at the Courant number on a grid of spacing h (m), or steps of
    the longest dt_max (s; a solid's shear-wave step) where they are shorter, and the two
    steps fitted to the span's end."""
    return int(np.ceil(max(span * max_speed / (courant * h), span / dt_max))) + 3


def solid_history(count: int, dim: int) -> dict[str, Floats]:
    """A solid's history on its particles (src/core/plasticity.hpp), at the start: the
    deviatoric stress (count x D x D, Pa; zero: bodies start unstressed), the equivalent
    plastic strain and whether each particle yielded in the last step (count, 0 or 1)."""
    return {
        "stress": np.zeros((count, dim, dim)),
        "plastic_strain": np.zeros(count),
        "yielding": np.zeros(count),
    }


class Extra(TypedDict):
    """The core's optional particle arrays (None: not carried)."""

    affine: Floats | None
    stress: Floats | None
    plastic_strain: Floats | None
    yielding: Floats | None


class ProjectionScheme:
    SUPPORTS: ClassVar[frozenset[str]] = capabilities.SUPPORTS["projection"]

    def __init__(self, case: Case, grid: Grid, particles: Particles) -> None:
        s = case.solver
        self.case = case
        self.grid = grid
        self.apic = s.transfer == "apic"
        self.solid = materials.is_solid(case.material)
        self.open = bool(outlets.sides(case).any())  # outlets: particles leave the run
        self.outflow = outlets.Outflow()
        self.inlets = inlets.of_case(case, grid)  # inlets: particles enter the run
        self.inflow = inlets.Inflow()
        # with APIC also their affine matrices (zero); a solid's stress history (zero)
        self.particles = particles
        self.solids = obstacles.of_case(case, grid)
        self.viscous = materials.viscous_solve(case.material)
        cells = tuple(int(c) for c in grid.cells)
        T = (
            state.gauss_gradients(cells, float(grid.spacing))
            if self.viscous
            else np.zeros((0, 0, 0, 0))
        )
        self.walls = walls.of_case(case, grid, self.inlets.openings)
        self._load = loads.nodal(case, grid)  # surface loads: each node's force (None: none)
        # the nodes a load acts on (None: none)
        self._loaded = None if self._load is None else np.any(self._load != 0.0, axis=1)
        self.core = state.step_state(
            grid,
            self.walls.as_tuple(),
            self.solids,
            T,
            MARGIN * grid.spacing,
            preset(s.volume_correction, "volume_correction") > 0,
            self.viscous,
            outlets.sides(case) if self.open else (),
            bonded=self.walls.bonded,
            held=self.inlets.held if self.inlets.present else None,
            inlets=self.inlets.core() if self.inlets.present else None,
            damping=sponges.rates(case, grid),
            load=self._load,
        )
        if case.plate is not None:  # a rigid plate pressed on a saturated soil
            side = SIDE_NAMES.index(case.plate.side)
            self.core.set_plate(side // 2, 1 if side % 2 else -1, float(case.plate.force))
        # obstacles moving along prescribed paths (src/core/bodies.hpp), placed at t = 0
        self.movers = moving.of_case(case)
        self.time = 0.0  # s: the flow time the core's bodies are placed at
        check_movers(case, grid, self.movers)
        if self.movers:
            self.core.set_bodies(
                [m.core(grid) for m in self.movers],
                self.solids.node_no_slip,
                0 if self.solid else obstacles.SUBCELLS,  # a solid's tools: the staircase
            )
        # amg, direct, petsc: solvers from Python, plugged into the compiled step
        self.python_solver = (
            None if s.linear_solver == "multigrid" else pressure.PythonSolver(grid, s)
        )
        if self.python_solver is not None:
            self.python_solver.use(self.core)
        if self.inlets.present:  # the next layers continue the bodies' lattice (k + 1/2) s
            self.core.inlet_travel[:] = self.inlets.row_spacing() / 2
        self.steps = 0  # steps taken: the volume correction runs on every n-th (n from dt)
        self.last_unknowns = 0
        self.auto = case.time.dt == "auto"  # steps set by the flow (advance_span)
        self.dt_range = [np.inf, 0.0]  # the shortest and longest step taken (auto)

    @property
    def particles(self) -> Particles:
        return self._P

    @particles.setter
    def particles(self, P: Particles) -> None:
        """The particles the scheme moves. With solver.transfer = "apic" each also carries its
        affine velocity matrix C_p (``affine``, count x D x D, 1/s), here set to 0: bodies
        start at rest or in uniform motion, whose velocity gradient is 0. None with FLIP/PIC
        (the core then runs the FLIP/PIC transfers)."""
        self._P = P
        D = self.grid.dim
        self.affine: Floats | None = np.zeros((P.count, D, D)) if self.apic else None
        self.history = solid_history(P.count, D) if self.solid else {}
        m = self.case.material
        if m.model in materials.SATURATED and m.initial_stress == "geostatic":
            self.history["stress"][:] = poroelastic.geostatic_stress(
                m, P.x, P.mass, P.volume, np.asarray(self.case.physics.gravity, dtype=float)
            )
        # with outlets, the particles' own mass and volume: the core zeroes a retired one's
        self._own = (P.mass.copy(), P.volume.copy()) if self.open else None

    def _supply(self, duration: float) -> None:
        """Before a chunk of ``duration`` (s): the inlets' pool of dormant particles at the
        end of the particle arrays (src/core/inlets.hpp)."""
        if not self.inlets.present:
            return
        size = self.inlets.pool_size(self.core.inlet_travel, duration)
        extra = [] if self.affine is None else [self.affine]
        first, end = self.inflow.supply(self._P, size, extra)
        if self.affine is not None:
            self.affine = extra[0]
        self.core.set_inlet_pool(first, end)

    def _settle(self) -> None:
        """After a chunk: the pool's emitted particles kept and counted, the rest removed."""
        if not self.inlets.present:
            return
        first = self.inflow.pool[0]
        emitted = int(self.core.inlet_next) - first
        keep = self.inflow.settle(self._P, first + emitted, self.inlets.particle)
        if keep is not None and self.affine is not None:
            self.affine = self.affine[keep]
        if self._own is not None:  # the emitted particles' own mass and volume
            m, V = self.inlets.particle
            self._own = (
                np.concatenate([self._own[0], np.full(emitted, m)]),
                np.concatenate([self._own[1], np.full(emitted, V)]),
            )

    def _drain(self) -> None:
        """Remove the particles that left through an outlet in the last chunk."""
        if self._own is None:
            return
        keep = self.outflow.drain(self._P, *self._own)
        if keep is not None:
            self._own = (self._own[0][keep], self._own[1][keep])
            if self.affine is not None:
                self.affine = self.affine[keep]
            self.history = {k: a[keep] for k, a in self.history.items()}

    @property
    def p_node(self) -> Floats:
        """The nodal pressure of the last step (Pa)."""
        return self.core.p_node

    def options(self, dt: float) -> CoreOptions:
        """The compiled step's settings for steps of dt (``Options2``/``Options3``)."""
        s, m = self.case.solver, self.case.material
        volume_rate = preset(s.volume_correction, "volume_correction")
        flip = preset(s.flip, "flip")
        every = max(1, round(s.volume_correction_interval / dt)) if volume_rate > 0 else 0
        particles = s.partial_cell_quadrature == "particles"
        model, params = materials.parameters(m)
        padded = np.zeros(MODEL_PARAMETERS)
        padded[: len(params)] = params
        shallow, shallow_max_dt = shallow_nodes(self.case)
        return state.step_options(
            self.grid.dim,
            dt=float(dt),
            gravity=[float(g) for g in self.case.physics.gravity],
            rho=float(m.density),
            flip=state.flip_per_step(flip, dt),
            full=float(s.full_cell_threshold),
            sparse=float(preset(s.sparse_cell_threshold, "sparse_cell_threshold")),
            partial_particles=particles,
            cell_pressure=materials.is_solid(m),
            # past a solid's shear-wave step, the elastic solve and the projection as one
            # system (docs/method.md, "Solids"): the split grows a bending beam there
            coupled=materials.coupled_step(m, self.grid.spacing, dt),
            surface=(
                state.SURFACE_QUADRATURE["gauss"]
                if particles
                else state.SURFACE_QUADRATURE[preset(s.surface_quadrature, "surface_quadrature")]
            ),
            subcell=s.free_surface == "subcell",
            wall_flux=bool(s.wall_flux),
            theta_min=float(s.ghost_theta_min),
            shallow=shallow,
            shallow_max_dt=shallow_max_dt,
            expansion=float(preset(s.density_correction, "density_correction")),
            tol=float(s.tolerance),
            max_iterations=int(s.max_iterations),
            sweeps=SMOOTHING_SWEEPS,
            volume_rate=float(volume_rate),
            volume_every=int(every),
            volume_tol=float(s.volume_correction_tolerance),
            volume_max_iterations=volume_correction.MAX_ITERATIONS,
            volume_dmax=volume_correction.MAX_DISPLACEMENT,
            viscous=self.viscous,
            model=int(model),
            model_params=[float(v) for v in padded],
            courant=float(self.case.time.courant),
            dt_max=float(longest_projection_step(self.case)),
            flip_rate=float(flip),
            volume_interval=float(s.volume_correction_interval),
        )

    def body_values(self) -> tuple[Floats, Floats, Floats]:
        """The moving obstacles' force (bodies x D, N; 2D N/m), torque (bodies x 3) and state
        (``State.body_state``: pivot, velocity, angular velocity, orientation) after the
        last step, in the domain's frame (over MPI ranks too: the core sums the ranks'
        shares and moves the bodies in the domain's frame on every rank)."""
        core = self.core
        return core.body_force.copy(), core.body_torque.copy(), core.body_state.copy()

    def state(self) -> dict[str, NDArray[Any]]:
        """What the scheme carries from one step to the next beyond the particles: the nodal
        pressure and the volume correction's last solution (the warm starts of the next
        solves), and with APIC the particles' affine matrices. Everything else is rebuilt
        each step."""
        saved = {
            "p_node": self.core.p_node.copy(),
            "last_unknowns": np.array(self.last_unknowns),
            "steps": np.array(self.steps),
            "since_volume": np.array(self.core.since_volume),
            "dt_range": np.array(self.dt_range),
            "time": np.array(self.time),
        }
        if materials.is_solid(self.case.material):  # a solid's pressure is the cells'
            saved["p_cell"] = self.core.p_cell.copy()
        if self.case.plate is not None:  # the plate's velocity, the next step's first guess
            saved["plate_velocity"] = np.array(self.core.plate_velocity)
        if self.movers:  # the free bodies' poses and velocities
            saved["body_state"] = self.core.body_state.copy()
        q = self.core.volume_q
        if q.size:
            saved["volume_q"] = q.copy()
        if self.affine is not None:
            saved["affine"] = self.affine.copy()
        for name, a in self.history.items():
            saved[name] = a.copy()
        if self.open:
            saved["outflow"] = self.outflow.as_array()
        if self.inlets.present:
            saved["inflow"] = self.inflow.as_array()
            saved["inlet_travel"] = self.core.inlet_travel.copy()
        return saved

    def restore(self, saved: dict[str, NDArray[Any]]) -> None:
        """Continue from ``state()`` (a checkpoint)."""
        np.copyto(self.core.p_node, saved["p_node"])
        if "p_cell" in saved:  # a solid's cell pressure (checkpoints before it carry none)
            np.copyto(self.core.p_cell, saved["p_cell"])
        if self.case.plate is not None:
            self.core.plate_velocity = float(saved["plate_velocity"])
        self.last_unknowns = int(saved["last_unknowns"])
        self.steps = int(saved["steps"])
        if "since_volume" in saved:  # checkpoints written before adaptive steps lack them
            self.core.since_volume = float(saved["since_volume"])
            self.dt_range = [float(t) for t in saved["dt_range"]]
        if "time" in saved:  # checkpoints written before moving obstacles lack it
            self.time = float(saved["time"])
            self.core.time = self.time
        if self.movers:
            self.core.body_state = np.ascontiguousarray(saved["body_state"], dtype=float)
        q = self.core.volume_q
        if q.size:
            np.copyto(q, saved["volume_q"])
        if self.open:
            self.outflow = outlets.Outflow.of_array(saved["outflow"])
        if self.inlets.present:
            self.inflow = inlets.Inflow.of_array(saved["inflow"])
            np.copyto(self.core.inlet_travel, saved["inlet_travel"])
        if self.affine is not None:
            affine = saved["affine"]  # KeyError, or ValueError if its shape differs
            if affine.shape != self.affine.shape:
                raise ValueError(
                    f"affine matrices of shape {affine.shape}, the particles "
                    f"need {self.affine.shape}"
                )
            np.copyto(self.affine, affine)
        for name, a in self.history.items():
            kept = saved[name]  # KeyError: a checkpoint of a fluid continued as a solid
            if kept.shape != a.shape:
                raise ValueError(f"{name} of shape {kept.shape}, the particles need {a.shape}")
            np.copyto(a, kept)

    def _extra(self) -> Extra:
        """The core's optional particle arrays: APIC's affine matrices, a solid's history."""
        h = self.history
        return Extra(
            affine=self.affine,
            stress=h.get("stress"),
            plastic_strain=h.get("plastic_strain"),
            yielding=h.get("yielding"),
        )

    def _particles(self) -> ParticleArrays:
        P = self.particles
        return P.x, P.v, P.mass, P.volume, P.pressure

    def check_free_surface(self) -> None:
        """Raise SolverError ("singular") when the material as placed touches no free
        surface: the first step's classification and assembly, without the solve (its
        buffers are overwritten by the step). Lets a run refuse such a case before it
        starts instead of failing at step 1."""
        # a long step: every node with f > 1/2 an unknown (a small step's shallow nodes only
        # move the rows beside the air one node in, and a surface is found either way)
        O = self.options(1.0)
        if O.cell_pressure:  # a solid's surface is natural: no level to refer to
            return
        n = self.core.predict(*self._particles(), O, False, **self._extra())
        if n and not self.core.pressure_matrix(O):
            raise pressure.singular(" at the start")

    def advance(
        self, dt: float, nsteps: int, where: Callable[[int], str] = lambda k: ""
    ) -> StepReport:
        """``nsteps`` steps of size dt; ``where(k)`` names step k in messages. The report sums
        the steps (residual: the worst)."""
        O = self.options(dt)
        report = state.Report()
        self._supply(dt * nsteps)
        if self.movers:  # the bodies where this chunk starts (the core's own sum may drift)
            self.core.time = self.time
        if self.auto:
            return self._adaptive(O, dt * nsteps, report, where)
        try:
            done = self.core.advance(
                *self._particles(), O, self.steps + 1, nsteps, report, **self._extra()
            )
        except pressure.SETUP_ERRORS as err:
            k = int(report.step)
            self.steps += k
            raise pressure.setup_failed(where(k), err, int(report.last_unknowns)) from err
        finally:
            self._settle()
            self._drain()
        self.steps += done
        self.time += done * dt
        self.last_unknowns = int(report.last_unknowns)
        if done < nsteps:
            self._fail(report, where(done))
        self._check_loads(where(done))
        return StepReport.of(report)

    def _adaptive(
        self, O: CoreOptions, span: float, report: CoreReport, where: Callable[[int], str]
    ) -> AdaptiveReport:
        """time.dt = "auto": steps set by the flow over the span (``State.advance_span``)."""
        s = self.case.solver
        most = most_steps(span, s.max_speed, O.courant, self.grid.spacing, O.dt_max)
        try:
            covered = self.core.advance_span(
                *self._particles(), O, span, most, report, **self._extra()
            )
        except pressure.SETUP_ERRORS as err:
            k = int(report.steps)
            self.steps += k
            raise pressure.setup_failed(where(k), err, int(report.last_unknowns)) from err
        finally:
            self._settle()
            self._drain()
        done = int(report.steps)
        self.steps += done
        self.time += covered
        self.last_unknowns = int(report.last_unknowns)
        if done:
            self.dt_range = [
                min(self.dt_range[0], report.dt_min),
                max(self.dt_range[1], report.dt_max),
            ]
        if report.status != state.OK:
            self._fail(report, where(done))
        if covered < span * (1 - 1e-9):
            raise SolverError(
                f"The adaptive steps{where(done)} took {done} steps without reaching the next "
                f"output time: the flow is faster than solver.max_speed = {s.max_speed:g} m/s "
                "allows for. Raise solver.max_speed if such speeds are real, or use a fixed "
                "time.dt."
            )
        self._check_loads(where(done))
        r = StepReport.of(report)
        return AdaptiveReport(
            **vars(r), steps=done, dt_min=float(report.dt_min), dt_max=float(report.dt_max)
        )

    def darcy_flux(self) -> Floats:
        """A saturated soil's pore water flux relative to the skeleton at the particles
        (count x D, m/s; ``poroelastic.darcy_flux``) from the last step's nodal pore
        pressure."""
        P, g = self._P, self.grid
        gravity = np.asarray(self.case.physics.gravity, dtype=float)
        return poroelastic.darcy_flux(
            self.case.material,
            g.spacing,
            tuple(g.cells),
            self.core.p_node,
            P.x,
            P.mass,
            P.volume,
            gravity,
        )

    def _check_loads(self, where: str) -> None:
        """SimulationError where a surface load's node holds no material after the last
        step: the load would act on nothing there (the face has moved off its node plane)."""
        if self._loaded is None:
            return
        lost = self._loaded & (self.core.node_mass <= 0.0)
        if lost.any():
            x = self.grid.node_coordinates()[np.argmax(lost)]
            at = ", ".join(f"{c:.4g}" for c in x)
            raise SimulationError(
                f"A surface load{where} acts on a node without material, at ({at}) m: the "
                "loaded face has moved off the node plane of loads.N.at (a settlement or "
                "a heave past a cell), so the load would no longer reach the material. "
                "Give a finer grid.spacing than the face's motion, or a load that stays on "
                "the material."
            )

    def _fail(self, report: CoreReport, where: str) -> NoReturn:
        status = state.Status(int(report.status))
        n = int(report.fail_size)
        iterations = int(report.fail_iterations)
        residual = float(report.fail_residual)
        worst = int(report.fail_node)
        if status is state.Status.SINGULAR:
            raise pressure.singular(where)
        if status is state.Status.PRESSURE_NOT_CONVERGED:
            raise pressure.not_converged(
                where,
                residual,
                iterations,
                self.case.solver,
                n,
                self.grid.node_coordinates()[worst],
            )
        if status is state.Status.VOLUME_NOT_CONVERGED:
            raise volume_correction.not_converged(where, residual, iterations, n)
        if status is state.Status.VISCOUS_NOT_CONVERGED:
            m = self.case.material
            raise SolverError(
                f"The viscous solve did not converge{where}: relative residual "
                f"{residual:.3e} after {iterations} iterations (solver.tolerance = "
                f"{self.case.solver.tolerance:g}, solver.max_iterations = "
                f"{self.case.solver.max_iterations}); {n} unknowns (velocity components), "
                "largest residual at node ("
                + ", ".join(f"{c:.4g}" for c in self.grid.node_coordinates()[worst])
                + ") m. "
                "Try a smaller time.dt, a larger solver.max_iterations"
                + (
                    ", or a smaller material.max_viscosity"
                    if m.model in ("herschel_bulkley", "mu_i")
                    else ""
                )
                + "."
            )
        if status is state.Status.PLASTIC_NOT_CONVERGED:
            raise SolverError(
                f"The coupled step's plastic iterations did not settle{where}: a particle's "
                f"stress still moved by {residual:.3e} of the largest (the tolerance 1e-3) "
                f'after {iterations} iterations, each a coupled solve (docs/method.md, "Solids"). '
                "The step is too far past the shear wave's crossing of a cell for this flow: "
                'try a smaller time.dt (time.dt = "auto" takes the solid\'s own step).'
            )
        raise SolverError(f"The step failed{where} with status {status.name}.")


def check_movers(case: Case, grid: Grid, movers: list[moving.Mover]) -> None:
    """Refuse moving obstacles the step cannot follow: across a periodic axis, or faster
    than a cell a step at a fixed time.dt (time.dt = "auto" counts their speed)."""
    if not movers:
        return
    if any(case.domain.periodic or []):
        raise CaseError(
            f"obstacles.{movers[0].index}.motion: moving obstacles in a periodic domain are not "
            "supported yet; remove domain.periodic or the motion"
        )
    free = [m for m in movers if m.free is not None]
    if free and not preset(case.solver.wall_flux, "wall_flux"):
        raise CaseError(
            f"obstacles.{free[0].index}.motion: a free body is coupled to the pressure through "
            "the obstacle's face term, which solver.wall_flux = false leaves out; set "
            "solver.wall_flux = true"
        )
    if case.time.dt == "auto":
        return
    dt = float(case.time.dt)
    for m in movers:
        if m.free is not None:  # its speed is the flow's: time.dt = "auto" follows it
            continue
        speed = m.max_speed()
        if speed * dt > grid.spacing:
            raise CaseError(
                f"obstacles.{m.index}.motion moves the obstacle at up to {speed:.4g} m/s, more "
                f"than a cell ({grid.spacing:g} m) in a step of time.dt = {dt:g} s; give "
                f'time.dt <= {grid.spacing / speed:.3g} s, or time.dt = "auto"'
            )
