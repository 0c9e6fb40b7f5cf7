"""The projection scheme on several MPI ranks (issue 28; docs/design/mpi.md, section 2).

Each rank steps the particles of its box of cells (``boxes``) on its local grid (the box and
one ghost layer, ``subgrid``) with the core's phases, and the ranks meet where a step needs
its neighbours:

1. the halo: copies of the neighbours' particles in the ghost layer (``exchange.halo``);
2. ``scatter`` (particle-to-grid, nodal fractions), then the owners' node values at the
   nodes a rank holds without owning them (``NodeExchange.fill``), then ``classify``;
3. which nodes are pressure unknowns is the owner's decision (``renumber``); each rank's
   owned unknowns are numbered after those of the ranks before it; a viscous material's
   predictor is solved over the ranks likewise (``viscous``);
4. the pressure system: each rank assembles its rows, PETSc solves (``petsc``), the
   solution reaches the nodes round each box, the walls release and the system is solved
   again while any rank released one;
5. the ghost pressures, the owners' values again, the corrector, grid-to-particle on the
   owned particles; then each particle goes to the rank that owns its new cell.

Between chunks (at the output times) every rank holds the whole particle set and nodal
pressure, gathered in the particles' original order: the Simulation's measures, probes,
outputs and checkpoints see what a one-process run sees, and a checkpoint restarts on any
number of ranks. The boxes are split again at a chunk's start when the particles per rank
fall below ``BALANCE`` of their mean.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np
from numpy.typing import NDArray

from .. import materials, state
from ..arrays import Floats, Ints
from ..boundaries import inlets, obstacles, outlets, walls
from ..errors import SolverError
from ..grid import Grid
from ..particles import Particles
from ..schemes import pressure
from ..schemes.projection import (
    MARGIN,
    AdaptiveReport,
    ProjectionScheme,
    StepReport,
    most_steps,
    preset,
)
from ..schemes.projection import ParticleArrays as CoreParticles
from ..state import CoreOptions, CoreReport
from .boxes import Boxes, bisect, cell_weights
from .comm import Comm, world
from .exchange import Halo, NodeExchange, ParticleArrays, migrate, owners
from .petsc import DistributedSystem
from .pockets import sealed_pockets
from .subgrid import neighbours, restrict_obstacles, restrict_walls, subgrid
from .viscous import DistributedViscous
from .volume import DistributedVolume

if TYPE_CHECKING:
    from ..case import Case

# re-split when the fewest-loaded measure falls below this share of the largest: the step
# waits for the slowest rank, so below 0.8 a fifth of the machine idles; measured at chunk
# starts only (a re-split costs a rebuild of the local state, a few steps' time)
BALANCE = 0.8
Numbered = tuple[Ints, int, int, Floats]  # owned rows, first global row, count, global numbers
FIELDS = ("x", "v", "mass", "volume", "pressure")


class DistributedProjection(ProjectionScheme):
    """``ProjectionScheme`` over the ranks of ``comm`` (the run's MPI world)."""

    SUPPORTS: ClassVar[frozenset[str]] = frozenset({"obstacles"})

    def __init__(self, case: Case, grid: Grid, particles: Particles) -> None:
        s = case.solver
        self.case = case
        self.grid = grid
        self.comm: Comm = world()
        self.apic = s.transfer == "apic"
        self.open = False
        self.outflow = outlets.Outflow()  # none: outlets are refused on several ranks
        self.inflow = inlets.Inflow()  # none: inlets are refused on several ranks
        self.viscous = materials.is_viscous(case.material)
        self.viscous_solve = DistributedViscous(
            self.comm, s.tolerance, s.max_iterations, s.petsc_preconditioner
        )
        self.solids = obstacles.of_case(case, grid)
        self._walls = walls.of_case(case, grid).as_tuple()
        self.system = DistributedSystem(s.tolerance, s.max_iterations, s.petsc_preconditioner)
        self.corrects = bool(preset(s.volume_correction, "volume_correction") > 0)
        self.volume = DistributedVolume(self.comm, s.tolerance, s.petsc_preconditioner)
        self.steps = 0
        self.last_unknowns = 0
        self.auto = case.time.dt == "auto"  # steps set by the flow (``_span``)
        self.since_volume = 0.0  # the flow time since the last volume correction (auto)
        self.dt_range = [np.inf, 0.0]
        self.p_global = np.zeros(grid.nnodes)
        # the volume correction's last solution on the whole grid's cells (the warm start
        # of its next solve; in checkpoints, which one process continues too)
        self.q_global = np.zeros(grid.ncells if self.corrects else 0)
        self.boxes: Boxes | None = None
        self.balance = 1.0  # particles per rank: the least loaded over the most
        self.splits = 0
        self.step_seconds = 0.0  # this rank's time in steps, and in PETSc's set-up and solves
        self.solve_seconds = 0.0
        self.ranks_report: dict[str, Any] = {}
        self.last_owned = 0  # this rank's pressure unknowns in the last step
        self.node_bytes = 0  # sent in node fills under earlier splits
        # what this rank received or sent, summed over its steps (benchmarks/mpi/)
        self.traffic = dict.fromkeys(
            ("steps", "halo particles", "migrated particles", "ghost columns", "iterations"), 0
        )
        self.particles = particles

    # the particles: every rank holds them all between chunks
    @property
    def particles(self) -> Particles:
        return self._P

    @particles.setter
    def particles(self, P: Particles) -> None:
        """The whole particle set; with APIC also their affine matrices (zero, as the
        one-process scheme starts them)."""
        self._P = P
        D = self.grid.dim
        self.affine: Floats | None = np.zeros((P.count, D, D)) if self.apic else None
        self.fields = FIELDS + (("affine",) if self.apic else ())

    def _whole(self, field: str) -> NDArray[Any]:
        """The whole set's array of a field (the particles', or the affine matrices)."""
        if field == "affine":
            assert self.affine is not None
            return self.affine
        whole: NDArray[Any] = getattr(self._P, field)
        return whole

    @property
    def p_node(self) -> Floats:
        return self.p_global

    # --- the split and the local state ---------------------------------------------------
    def _split(self) -> None:
        """Split the grid into boxes on the particles' places (again when the load is
        uneven), and build this rank's local grid, tables and compiled state."""
        g = self.grid
        if self.boxes is not None:
            self._owners()
            if self.balance >= BALANCE:
                return
        self.boxes = bisect(cell_weights(self._P.x, g.spacing, g.cells), self.comm.size)
        self.splits += 1
        sub = subgrid(g, self.boxes, self.comm.rank)
        self.sub = sub
        if self.splits > 1:  # what the last split's exchange sent
            self.node_bytes += self.nodes.sent
        self.nodes: NodeExchange = NodeExchange(self.comm, sub)
        self.cells = NodeExchange(self.comm, sub, cells=True)
        self.neighbours = neighbours(self.boxes, self.comm.rank)
        self.halo = Halo(self.comm, self.boxes, sub, self.neighbours)
        self.foreign = ~sub.owned_nodes
        offset = sub.offset
        cells = tuple(int(c) for c in sub.grid.cells)
        self.core = state.step_state(
            sub.grid,
            restrict_walls(self._walls, sub),
            restrict_obstacles(self.solids, sub),
            (
                state.gauss_gradients(cells, float(g.spacing))
                if self.viscous
                else np.zeros((0, 0, 0, 0))
            ),
            MARGIN * g.spacing,
            self.corrects,
            self.viscous,
            (),
            lower=[-float(o) for o in offset],
            upper=[float(u) - float(o) for u, o in zip(g.size, offset)],
        )
        self._owners()

    def _owners(self) -> None:
        """Each particle's rank under the current boxes, and the balance they give."""
        assert self.boxes is not None
        self._owner = self.boxes.owner_of_points(self._P.x, self.grid.spacing)
        load = np.bincount(self._owner, minlength=self.comm.size)
        self.balance = float(load.min() / max(load.max(), 1))

    def _distribute(self) -> ParticleArrays:
        """This rank's particles (global coordinates) with their numbers (``_split`` has
        just found each one's rank)."""
        mine = np.flatnonzero(self._owner == self.comm.rank)
        owned = {f: self._whole(f)[mine].copy() for f in self.fields}
        owned["id"] = mine.astype(np.int64)
        return owned

    def _gather(self, owned: ParticleArrays) -> None:
        """Every rank's particles back into the whole set, in their original order, and
        the nodal pressure of the owned nodes into the whole grid's."""
        parts = self.comm.allgather(owned)
        ids = np.concatenate([p["id"] for p in parts])
        if ids.size != self._P.count or np.unique(ids).size != ids.size:
            raise SolverError(
                f"Particles were lost or doubled between ranks: {ids.size} gathered, "
                f"{self._P.count} in the run."
            )
        for f in self.fields:
            self._whole(f)[ids] = np.concatenate([p[f] for p in parts])
        sub = self.sub
        mine = sub.owned_nodes
        pieces = self.comm.allgather((sub.node_global[mine], self.core.p_node[mine]))
        for index, values in pieces:
            self.p_global[index] = values
        if self.q_global.size and self.core.volume_q.size:
            cells = sub.owned_cells
            parts = self.comm.allgather((sub.cell_global[cells], self.core.volume_q[cells]))
            for index, values in parts:
                self.q_global[index] = values

    def _report(self, owned: ParticleArrays) -> None:
        """The load of each rank (summary.json's "mpi"): particles now, unknowns of the
        last step, seconds in steps and in PETSc so far; balance = least / most particles."""
        mine = (int(owned["id"].size), int(self.last_owned), self.step_seconds, self.solve_seconds)
        loads = self.comm.allgather(mine)
        particles = [p for p, _, _, _ in loads]
        self.ranks_report = {
            "ranks": self.comm.size,
            "particles": particles,
            "unknowns": [u for _, u, _, _ in loads],
            "step_seconds": [round(t, 3) for _, _, t, _ in loads],
            "solve_seconds": [round(t, 3) for _, _, _, t in loads],
            "balance": round(min(particles) / max(max(particles), 1), 3),
            "splits": self.splits,
            "pressure": f"PETSc CG + {self.case.solver.petsc_preconditioner}",
            "node_bytes_sent": self.comm.allgather(self.node_bytes + self.nodes.sent),
            "traffic": self.comm.allgather(dict(self.traffic)),
        }

    # --- one step -------------------------------------------------------------------------
    def _local(self, owned: ParticleArrays) -> ParticleArrays:
        """The core's particle arrays: the owned particles, then the halo, in the local
        grid's coordinates."""
        assert self.boxes is not None
        ghosts = self.halo(owned)
        self.traffic["halo particles"] += int(ghosts["id"].size)
        arrays = {f: np.concatenate([owned[f], ghosts[f]]) for f in self.fields}
        arrays["x"] -= self.sub.offset
        return {f: np.ascontiguousarray(a) for f, a in arrays.items()}

    @staticmethod
    def _core_arrays(arrays: ParticleArrays, m: int | None = None) -> CoreParticles:
        """x, v, mass, volume, pressure (the first m particles: None, all) for the core."""
        a = arrays
        return a["x"][:m], a["v"][:m], a["mass"][:m], a["volume"][:m], a["pressure"][:m]

    def _owned_contacts(self) -> int:
        mine = self.sub.owned_nodes
        return int(self.core.contact[mine].sum() + self.core.ocontact[mine].sum())

    def _number(self, O: CoreOptions) -> Numbered:
        """Classify with the owners' say on the nodes round the box; number the owned
        unknowns after the ranks before. Returns the owned rows (local row numbers), the
        first global row, the global count and each local row's global number."""
        core = self.core
        unknown = (core.node_row >= 0).astype(float)
        self.nodes.fill(unknown)
        rows = core.node_row
        rows[self.foreign] = np.where(unknown[self.foreign] > 0, 0, -1)
        core.renumber()
        local_rows = core.rows
        owned = np.flatnonzero(self.sub.owned_nodes[local_rows])
        counts = self.comm.allgather(int(owned.size))
        first = int(sum(counts[: self.comm.rank]))
        number = np.full(self.sub.grid.nnodes, -1.0)
        number[local_rows[owned]] = first + np.arange(owned.size)
        self.nodes.fill(number)
        return owned, first, int(sum(counts)), number[local_rows]

    def _pressure(self, O: CoreOptions, report: CoreReport, where: str, numbered: Numbered) -> None:
        """The pressure solve on the unknowns ``_number`` numbered."""
        core = self.core
        owned, first, n, number = numbered
        self.last_owned = owned.size
        report.unknowns = max(int(report.unknowns), n)
        report.last_unknowns = n
        core.warm_start()
        x0 = core.x0[owned].copy()
        core.pressure_matrix(O)
        if n == 0:
            return
        air = core.anchored[owned]  # the rows next to a free surface
        if not self.comm.allreduce(int(air.any())):
            raise pressure.singular(where)
        cols = core.matrix_cols[owned]
        global_cols = np.where(cols >= 0, number[np.maximum(cols, 0)], -1).astype(np.int64)
        # every rank decides together: one rank raising alone would leave the others
        # waiting in the next exchange
        if self.comm.allreduce(int(np.any((cols >= 0) & (global_cols < 0)))):
            raise SolverError(f"A pressure row{where} couples to a node no rank numbered.")
        nn = self.sub.grid.nnodes
        if sealed_pockets(self.comm, self.nodes, core.matrix_cols, core.rows, owned, air, nn):
            raise SolverError(
                f"Water sealed off from the free surface{where} lies across ranks: such "
                "pockets are held at their top on one process only. Run this case on one "
                "process."
            )
        clock = time.perf_counter()
        self.system.prepare(first, global_cols, core.matrix_vals[owned].copy(), n)
        self.solve_seconds += time.perf_counter() - clock
        self.traffic["ghost columns"] += self.system.ghost_columns
        iterations = 0
        while True:
            core.pressure_rhs(O)
            clock = time.perf_counter()
            result = self.system.solve(core.rhs[owned].copy(), x0)
            self.solve_seconds += time.perf_counter() - clock
            report.solves += 1
            report.iterations += result.iterations
            self.traffic["iterations"] += result.iterations
            iterations += result.iterations
            report.residual = max(float(report.residual), result.residual)
            if not result.converged:
                raise pressure.not_converged(
                    where,
                    result.residual,
                    result.iterations,
                    self.case.solver,
                    n,
                    self._worst(core.rhs[owned].copy(), result.x, core.rows[owned]),
                )
            p = np.zeros(self.sub.grid.nnodes)
            p[core.rows[owned]] = result.x
            self.nodes.fill(p)
            before = self._owned_contacts()
            core.release_walls(np.ascontiguousarray(p[core.rows]))
            released = self.comm.allreduce(before - self._owned_contacts())
            if released == 0:
                break
            report.released += released
            x0 = result.x
        report.max_iterations = max(int(report.max_iterations), iterations)
        core.extend_pressure(O)
        self.nodes.fill(core.p_node)

    def _worst(self, b: Floats, x: Floats, nodes: Ints) -> Floats:
        """The position of the largest residual over all ranks (collective)."""
        r = np.abs(self.system.residual(b, x))
        mine = (-1.0, np.zeros(self.grid.dim))
        if r.size:
            k = int(np.argmax(r))
            mine = (float(r[k]), self.sub.node_position(int(nodes[k])))
        worst: Floats = max(self.comm.allgather(mine), key=lambda item: item[0])[1]
        return worst

    def _predict(self, owned: ParticleArrays, O: CoreOptions, correct: bool) -> ParticleArrays:
        """The step up to the pressure system (the core's ``predict``), with the owners'
        values at the nodes (and cells) round the box; returns the core's particle arrays
        (owned, then the halo)."""
        core = self.core
        local = self._local(owned)
        core.scatter(*self._core_arrays(local), O, correct, affine=local.get("affine"))
        self.nodes.fill(core.node_mass, core.node_vol, core.v_old, core.v_star, core.node_f)
        if correct:  # the cells' particle volume reaches past a cell: the owners' sums
            self.cells.fill(core.cell_vol)
        core.classify(*self._core_arrays(local), O)
        return local

    def _step(
        self, owned: ParticleArrays, O: CoreOptions, report: CoreReport, where: str, correct: bool
    ) -> ParticleArrays:
        """One step of the owned particles (``correct``: with the volume correction)."""
        core = self.core
        local = self._predict(owned, O, correct)
        affine = local.get("affine")
        # the owners' classification first: the viscous step's walls hold by it
        numbered = self._number(O)
        if self.viscous:
            self.viscous_solve.predict(core, self.sub, self.nodes, O, report, where)
        self._pressure(O, report, where, numbered)
        core.correct(O)
        if correct:
            self.volume.correct(core, self.sub, self.cells, O, report, where)
        m = owned["x"].shape[0]
        mine = None if affine is None else affine[:m]
        core.to_particles(*self._core_arrays(local, m), O, correct, affine=mine)
        moved = {f: a[:m] for f, a in local.items()}
        moved["x"] = moved["x"] + self.sub.offset
        moved["id"] = owned["id"]
        assert self.boxes is not None
        owner = owners(self.boxes, self.sub, moved["x"])
        self.traffic["migrated particles"] += int((owner != self.comm.rank).sum())
        self.traffic["steps"] += 1
        return migrate(self.comm, owner, moved, self.neighbours)

    def advance(
        self, dt: float, nsteps: int, where: Callable[[int], str] = lambda k: ""
    ) -> StepReport:
        """nsteps steps of dt, or with time.dt = "auto" steps set by the flow over the span
        dt x nsteps (the rule of the core's ``State::advance_span``)."""
        self._split()
        O = self.options(dt)
        O.pockets = False
        report = state.Report()
        self.core.p_node[:] = self.p_global[self.sub.node_global]
        if self.q_global.size and self.core.volume_q.size:
            self.core.volume_q[:] = self.q_global[self.sub.cell_global]
        self._owned = self._distribute()
        clock = time.perf_counter()
        try:
            if self.auto:
                done = self._span(O, dt * nsteps, report, where)
            else:
                for k in range(nsteps):
                    report.step = k
                    # the volume correction every n-th step
                    correct = state.volume_due_fixed(self.steps + k + 1, O.volume_every)
                    self._owned = self._step(self._owned, O, report, where(k), correct)
                done = nsteps
        finally:
            self.step_seconds += time.perf_counter() - clock
            self._gather(self._owned)
            self._report(self._owned)
        self.steps += done
        self.last_unknowns = int(report.last_unknowns)
        r = StepReport.of(report)
        r.moved_inside = int(self.comm.allreduce(int(report.moved)))
        r.capped = int(self.comm.allreduce(int(report.capped)))
        if not self.auto:
            return r
        self.dt_range = [min(self.dt_range[0], report.dt_min), max(self.dt_range[1], report.dt_max)]
        return AdaptiveReport(
            **vars(r), steps=done, dt_min=float(report.dt_min), dt_max=float(report.dt_max)
        )

    def _span(
        self, O: CoreOptions, span: float, report: CoreReport, where: Callable[[int], str]
    ) -> int:
        """Steps of adaptive size over the span (s), by the core's rules (``adaptive_dt``,
        ``volume_due_adaptive``: src/core/step.hpp) on the largest particle speed over all
        ranks, as ``State::advance_span`` takes them. Returns the steps taken."""
        s = self.case.solver
        h = self.grid.spacing
        most = most_steps(span, s.max_speed, O.courant, h, O.dt_max)
        elapsed, done = 0.0, 0
        while done < most and elapsed < span:
            report.step = done
            v = self._owned["v"]
            mine = float(np.max(np.sum(v * v, axis=1))) if v.shape[0] else 0.0
            vmax2 = max(self.comm.allgather(mine))
            rest = span - elapsed
            dt = state.adaptive_dt(vmax2, O.courant, h, O.dt_max, rest)
            O.dt = dt
            O.flip = state.flip_per_step(O.flip_rate, dt)
            correct, self.since_volume = state.volume_due_adaptive(
                self.since_volume, dt, O.volume_rate, O.volume_interval
            )
            self._owned = self._step(self._owned, O, report, where(done), correct)
            done += 1
            report.steps = done
            report.dt_min = dt if done == 1 else min(report.dt_min, dt)
            report.dt_max = max(report.dt_max, dt)
            elapsed = span if dt >= rest else elapsed + dt
        if elapsed < span * (1 - 1e-9):
            raise SolverError(
                f"The adaptive steps{where(done)} took {done} steps without reaching the next "
                f"output time: the flow is faster than solver.max_speed = {s.max_speed:g} m/s "
                "allows for. Raise solver.max_speed if such speeds are real, or use a fixed "
                "time.dt."
            )
        return done

    def owned_particles(self) -> ParticleArrays:
        """This rank's own particles (global coordinates, with their numbers ``id``, in
        their order in the run) between chunks: those of the last chunk's end, or before
        the first chunk those of the split's boxes (``parallel.snapshots``)."""
        owned = getattr(self, "_owned", None)
        if owned is None:
            self._split()
            owned = self._distribute()
        order = np.argsort(owned["id"], kind="stable")
        return {f: a[order] for f, a in owned.items()}

    def check_free_surface(self) -> None:
        """As ``ProjectionScheme.check_free_surface``, over the ranks."""
        self._split()
        O = self.options(1.0)
        O.pockets = False
        self._predict(self._distribute(), O, False)
        rows, _, n, _ = self._number(O)
        self.core.pressure_matrix(O)
        anchored = self.comm.allreduce(int(self.core.anchored[rows].any()))
        if n and not anchored:
            raise pressure.singular(" at the start")

    def state(self) -> dict[str, NDArray[Any]]:
        """As ``ProjectionScheme.state``: a checkpoint of the whole run, readable by one
        process or any number of ranks."""
        saved = {
            "p_node": self.p_global.copy(),
            "last_unknowns": np.array(self.last_unknowns),
            "steps": np.array(self.steps),
            "since_volume": np.array(self.since_volume),
            "dt_range": np.array(self.dt_range),
        }
        if self.q_global.size:
            saved["volume_q"] = self.q_global.copy()
        if self.affine is not None:
            saved["affine"] = self.affine.copy()
        return saved

    def restore(self, saved: dict[str, NDArray[Any]]) -> None:
        np.copyto(self.p_global, saved["p_node"])
        if self.q_global.size and "volume_q" in saved:  # written by one process, or ranks
            np.copyto(self.q_global, saved["volume_q"])
        self.last_unknowns = int(saved["last_unknowns"])
        self.steps = int(saved["steps"])
        if "since_volume" in saved:
            self.since_volume = float(saved["since_volume"])
            self.dt_range = [float(t) for t in saved["dt_range"]]
        if self.affine is not None:
            np.copyto(self.affine, saved["affine"])
