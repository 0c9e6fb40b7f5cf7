"""The projection scheme on several MPI ranks (issue 28; docs/design/mpi.md, section 2).

Each rank steps the particles of its box of cells (``boxes``) on its local grid (the box and
one ghost layer, ``subgrid``) with the core's own loop (``State.advance`` and
``advance_span``, the one-process loop): the step calls the rank's exchange
(``exchange.RankExchange``, through src/core/exchange.hpp) where it meets its neighbours,
and solves its systems with PETSc over the ranks (``pressure``, ``viscous``, ``volume``):

1. the halo: copies of the neighbours' particles in the ghost layer, after the rank's own;
2. ``scatter`` (particle-to-grid, nodal fractions), then the owners' node values at the
   nodes a rank holds without owning them, then ``classify`` with the owners' say on which
   of those nodes are pressure unknowns;
3. a viscous material's predictor, solved over the ranks;
4. the pressure system: each rank's owned unknowns are numbered after those of the ranks
   before, PETSc solves, the solution reaches the nodes round each box, the walls release
   and the system is solved again while any rank released one;
5. the corrector, the volume correction (solved over the ranks), grid-to-particle on the
   owned particles; then each particle goes to the rank that owns its new cell. The
   adaptive step's size comes from the largest speed over the ranks.

No rank holds the whole run (issue 42, item 3). Each rank seeds its own particles only
(``parallel.seeding``, with their numbers in the run: ``adopt``); given the whole run
instead (a one-process checkpoint, a test), the first split (``parted``: the first measure
or chunk) keeps each rank's own. From then on a rank holds its box's particles only, with
their numbers (``ids``), sorted by them: ``particles`` is this rank's part. The Simulation's measures
combine the parts (``diagnostics.parts``); snapshots and checkpoints are written in one
piece a rank (``parallel.snapshots``, ``simulation.checkpointer``), and a checkpoint
restarts on any number of ranks or on one process. What every rank does hold whole is
sized by the grid, not the particles: the nodal pressure and the cells' values a re-split
starts from. The boxes are split again at a chunk's start when the particles per rank fall
below ``BALANCE`` of the most loaded rank's; the particles then go to their new ranks in
one all-to-all.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import replace
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np
from numpy.typing import NDArray

from .. import materials, state
from ..arrays import Floats, Ints
from ..boundaries import inlets, moving, obstacles, outlets, walls
from ..errors import SolverError
from ..grid import Grid
from ..particles import Particles
from ..schemes import pressure
from ..schemes.projection import (
    MARGIN,
    AdaptiveReport,
    ProjectionScheme,
    StepReport,
    check_movers,
    most_steps,
    preset,
    solid_history,
)
from .boxes import Boxes, bisect, cell_weights
from .comm import Comm, sum_in_place, world
from .exchange import ParticleArrays, RankExchange
from .pressure import DistributedPressure
from .subgrid import ghost_layers, neighbours, restrict_obstacles, restrict_walls, subgrid
from .viscous import DistributedViscous
from .volume import DistributedVolume

if TYPE_CHECKING:
    from ..case import Case

# re-split when the fewest-loaded measure falls below this share of the largest: the step
# waits for the slowest rank, so below 0.8 a fifth of the machine idles; measured at chunk
# starts only (a re-split costs a rebuild of the local state, a few steps' time)
BALANCE = 0.8
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
        # a solid: its pressure per cell, its elastic predictor the viscous solve (eta = G
        # dt), its stress history on the particles, travelling with them between ranks
        self.solid = materials.is_solid(case.material)
        self.viscous = materials.viscous_solve(case.material)
        self.viscous_solve = DistributedViscous(
            self.comm, s.tolerance, s.max_iterations, s.petsc_preconditioner
        )
        self.solids = obstacles.of_case(case, grid)
        self._walls = walls.of_case(case, grid).as_tuple()
        # obstacles on prescribed paths: each rank places them on its own grid
        self.movers = moving.of_case(case)
        self.time = 0.0  # s: the flow time the bodies are placed at
        # the free bodies' state (State.body_state) where the last chunk ended: each split
        # builds a new core, whose bodies start where the case places them
        self.body_state: Floats | None = None
        check_movers(case, grid, self.movers)
        self.corrects = bool(preset(s.volume_correction, "volume_correction") > 0)
        self.volume = DistributedVolume(
            self.comm, s.volume_correction_tolerance, s.petsc_preconditioner
        )
        self.steps = 0
        self.last_unknowns = 0
        self.auto = case.time.dt == "auto"  # steps set by the flow (``_span``)
        self.since_volume = 0.0  # the flow time since the last volume correction (auto)
        self.dt_range = [np.inf, 0.0]
        self.p_global = np.zeros(grid.nnodes)
        # the volume correction's last solution on the whole grid's cells (the warm start
        # of its next solve; in checkpoints, which one process continues too)
        self.q_global = np.zeros(grid.ncells if self.corrects else 0)
        # a solid's cell pressure on the whole grid's cells (where its next step starts from)
        self.pc_global = np.zeros(grid.ncells if self.solid else 0)
        self.boxes: Boxes | None = None
        self._exchange: RankExchange | None = None  # this split's (``_split``)
        self.balance = 1.0  # particles per rank: the least loaded over the most
        self.splits = 0
        self.step_seconds = 0.0  # this rank's time in steps
        self.ranks_report: dict[str, Any] = {}
        self.node_bytes = 0  # sent in node fills under earlier splits
        # what this rank received or sent, summed over its steps (benchmarks/mpi/)
        self.traffic = dict.fromkeys(
            ("steps", "halo particles", "migrated particles", "ghost columns", "iterations"), 0
        )
        self.pressure = DistributedPressure(
            self.comm, s, s.petsc_preconditioner, self.traffic, cells=self.solid
        )
        self._where: Callable[[int], str] = lambda k: ""  # the chunk's names of its steps
        self.particles = particles

    # the particles: the whole run's on every rank until parted, then each rank's own
    @property
    def particles(self) -> Particles:
        return self._P

    @particles.setter
    def particles(self, P: Particles) -> None:
        """The whole particle set (every rank's the same, as seeded); with APIC also their
        affine matrices, a solid's stress history (zero, as the one-process scheme starts
        them). Parted at the first split."""
        self._P = P
        D = self.grid.dim
        self.affine: Floats | None = np.zeros((P.count, D, D)) if self.apic else None
        self.history = solid_history(P.count, D) if self.solid else {}
        self.fields = FIELDS + (("affine",) if self.apic else ()) + tuple(self.history)
        # the numbers in the run of this rank's particles (None: the whole run, in order)
        self.ids: Ints | None = None
        self.total = P.count  # the whole run's particles (no inlets or outlets on ranks)
        self.boxes = None  # a new set: split again (``restore`` may number it as a part)

    def adopt(self, ids: Ints) -> None:
        """The particles (``particles``) are this rank's part already, numbered ``ids`` in
        the run (``parallel.seeding``: seeded without the whole run); collective."""
        self.ids = np.asarray(ids, dtype=np.int64)
        self.total = int(self.comm.allreduce(int(self.ids.size)))
        self.boxes = None

    def parted(self) -> Comm:
        """The ranks, with the particles parted among them (each rank's own in
        ``particles``, their numbers in ``ids``); collective."""
        if self.boxes is None:
            self._split()
        return self.comm

    def _keep(self, owned: ParticleArrays) -> None:
        """This rank's particles from now on (``owned``: each field's rows and their
        numbers ``id``), sorted by number. The arrays of ``particles`` are replaced in its
        object, so that every holder (the Simulation) sees the part."""
        order = np.argsort(owned["id"], kind="stable")
        for f in Particles.FIELDS:
            setattr(self._P, f, owned[f][order])
        if self.affine is not None:
            self.affine = owned["affine"][order]
        for name in self.history:
            self.history[name] = owned[name][order]
        self.ids = owned["id"][order]

    def gathered(self) -> tuple[Particles, dict[str, NDArray[Any]]]:
        """The whole run's particles and a solid's history (with APIC also ``affine``) in
        the run's order, on every rank: one all-gather of every particle, for tests and
        small runs' checks; a run never calls it. Collective."""
        self.parted()
        owned = self._distribute()
        parts = self.comm.allgather(owned)
        ids = np.concatenate([p["id"] for p in parts])
        order = np.argsort(ids, kind="stable")
        whole = {f: np.concatenate([p[f] for p in parts])[order] for f in self.fields}
        P = Particles(*(whole.pop(f) for f in Particles.FIELDS))
        return P, whole

    def _whole(self, field: str) -> NDArray[Any]:
        """This rank's array of a field (the particles', the affine matrices or a solid's
        history): the whole run's until parted, then its part's."""
        if field == "affine":
            assert self.affine is not None
            return self.affine
        if field in self.history:
            return self.history[field]
        whole: NDArray[Any] = getattr(self._P, field)
        return whole

    @property
    def p_node(self) -> Floats:
        return self.p_global

    @property
    def exchange(self) -> RankExchange:
        """The exchange of the present split (this rank's, over MPI)."""
        if self._exchange is None:
            raise RuntimeError("DistributedProjection: no split yet")
        return self._exchange

    # --- the split and the local state ---------------------------------------------------
    def _split(self) -> None:
        """Split the grid into boxes on the particles' places (again when the load is
        uneven), build this rank's local grid, tables and compiled state, and send each
        particle to the rank that owns its cell. Collective."""
        g = self.grid
        if self.boxes is not None:
            self._weigh()
            if self.balance >= BALANCE:
                return
        weights = cell_weights(self._P.x, g.spacing, g.cells)
        if self.ids is not None:  # parted: the particles of every part (summed in place)
            weights = sum_in_place(self.comm, weights)
        boxes = bisect(weights, self.comm.size)
        self.boxes = replace(boxes, ghost=ghost_layers(bool(self.movers)))
        self.splits += 1
        sub = subgrid(g, self.boxes, self.comm.rank)
        self.sub = sub
        if self._exchange is not None:  # what the last split's exchange sent
            self.node_bytes += self._exchange.nodes.sent
        self._exchange = RankExchange(
            self.comm,
            self.boxes,
            sub,
            neighbours(self.boxes, self.comm.rank),
            self.fields,
            self.traffic,
        )
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
        if self.movers:  # their paths in the domain's frame (the core reads its grid's origin)
            no_slip = self.solids.node_no_slip
            local = no_slip[sub.node_global] if no_slip.size else no_slip
            nsub = 0 if self.solid else obstacles.SUBCELLS  # a solid's tools: the staircase
            self.core.set_bodies(
                [m.core(g) for m in self.movers], np.ascontiguousarray(local), nsub
            )
        # the core's loop steps this rank: its exchange and its solvers over the ranks
        self.core.use_exchange(
            self.exchange,
            np.ascontiguousarray(sub.owned_nodes, dtype=bool),
            np.ascontiguousarray(sub.owned_cells, dtype=bool),
        )
        where = self._step_name
        places = self.exchange.cells if self.solid else self.exchange.nodes
        self.pressure.bind(self.core, sub, places, where)
        self.viscous_solve.bind(self.core, sub, self.exchange.nodes, where)
        self.volume.bind(self.core, sub, self.exchange.cells, where)
        self.core.use_solvers(
            pressure=self.pressure,
            volume=self.volume if self.corrects else None,
            viscous=self.viscous_solve if self.viscous else None,
        )
        self._part(self.boxes.owner_of_points(self._P.x, g.spacing))

    def _part(self, owner: Ints) -> None:
        """Each particle to its rank (``owner``) under a new split: from the whole run
        every rank holds at the start, its own; from the parts, in one all-to-all."""
        comm = self.comm
        if self.ids is None:
            mine = np.flatnonzero(owner == comm.rank)
            kept = {f: self._whole(f)[mine] for f in self.fields}
            kept["id"] = mine.astype(np.int64)
        else:
            arrays = self._distribute()
            parts = comm.alltoall(
                [{f: a[owner == r] for f, a in arrays.items()} for r in range(comm.size)]
            )
            kept = {f: np.concatenate([p[f] for p in parts]) for f in arrays}
        self._keep(kept)
        self._weigh()

    def _weigh(self) -> None:
        """The balance of the parts: the fewest particles on a rank over the most."""
        loads = self.comm.allgather(self._P.count)
        self.balance = float(min(loads) / max(max(loads), 1))

    def _step_name(self) -> str:
        """The step in progress, as the chunk names it in messages."""
        return self._where(max(self.exchange.step - 1, 0))

    def _distribute(self) -> ParticleArrays:
        """This rank's particles (global coordinates) with their numbers, as the exchange
        takes them (the part's own arrays)."""
        assert self.ids is not None
        owned = {f: self._whole(f) for f in self.fields}
        owned["id"] = self.ids
        return owned

    def _gather(self, owned: ParticleArrays) -> None:
        """This rank's particles after a chunk (the exchange's), and the nodal pressure of
        the owned nodes into the whole grid's (and the cells' values a chunk starts from)."""
        self._keep(owned)
        total = self.comm.allreduce(int(self._P.count))
        if total != self.total:
            raise SolverError(
                f"Particles were lost or doubled between ranks: {total} on the ranks, "
                f"{self.total} in the run."
            )
        sub = self.sub
        mine = sub.owned_nodes
        pieces = self.comm.allgather((sub.node_global[mine], self.core.p_node[mine]))
        for index, values in pieces:
            self.p_global[index] = values
        # the cells' values the next chunk starts from (the volume correction's, a solid's
        # pressure), each from the rank owning the cell
        for whole, local in (
            (self.q_global, self.core.volume_q),
            (self.pc_global, self.core.p_cell),
        ):
            if whole.size and local.size:
                cells = sub.owned_cells
                for index, values in self.comm.allgather((sub.cell_global[cells], local[cells])):
                    whole[index] = values

    def _report(self) -> None:
        """The load of each rank (summary.json's "mpi"): particles now, unknowns of the
        last step, seconds in steps and in PETSc so far; balance = least / most particles."""
        mine = (
            self._P.count,
            int(self.pressure.last_owned),
            self.step_seconds,
            self.pressure.seconds,
        )
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
            "node_bytes_sent": self.comm.allgather(self.node_bytes + self.exchange.nodes.sent),
            "traffic": self.comm.allgather(dict(self.traffic)),
        }

    # --- a chunk of steps: the core's loop ----------------------------------------------
    def advance(
        self, dt: float, nsteps: int, where: Callable[[int], str] = lambda k: ""
    ) -> StepReport:
        """nsteps steps of dt, or with time.dt = "auto" steps set by the flow over the span
        dt x nsteps, taken by the core's loop (``State.advance``, ``advance_span``) on this
        rank's particles."""
        self._split()
        O = self.options(dt)
        O.pockets = False
        report = state.Report()
        core = self.core
        core.p_node[:] = self.p_global[self.sub.node_global]
        if self.q_global.size and core.volume_q.size:
            core.volume_q[:] = self.q_global[self.sub.cell_global]
        if self.pc_global.size:
            core.p_cell[:] = self.pc_global[self.sub.cell_global]
        core.since_volume = self.since_volume
        if self.movers:  # the bodies where this chunk starts
            core.time = self.time
            if self.body_state is not None:  # the free bodies' poses and velocities
                core.body_state = self.body_state
        self._where = where
        self.exchange.start(self._distribute())
        # the arrays the core is handed; its exchange gives each step the rank's own and halo
        own = self.exchange.owned
        arrays = (own["x"], own["v"], own["mass"], own["volume"], own["pressure"])
        span = dt * nsteps
        covered = span
        clock = time.perf_counter()
        try:
            if self.auto:
                s = self.case.solver
                most = most_steps(span, s.max_speed, O.courant, self.grid.spacing, O.dt_max)
                covered = core.advance_span(*arrays, O, span, most, report)
                done = int(report.steps)
            else:
                done = core.advance(*arrays, O, self.steps + 1, nsteps, report)
        finally:
            self.step_seconds += time.perf_counter() - clock
            self._gather(self.exchange.owned)
            self._report()
        self.since_volume = float(core.since_volume)
        if self.movers:  # the same on every rank (the core sums the ranks' shares)
            self.body_state = core.body_state.copy()
        self.steps += done
        self.time += covered if self.auto else done * dt
        self.last_unknowns = int(report.last_unknowns)
        if report.status != state.OK:
            self._fail(report, where(done))
        r = StepReport.of(report)
        r.moved_inside = int(self.comm.allreduce(int(report.moved)))
        r.capped = int(self.comm.allreduce(int(report.capped)))
        if not self.auto:
            return r
        if covered < span * (1 - 1e-9):
            raise SolverError(
                f"The adaptive steps{where(done)} took {done} steps without reaching the next "
                f"output time: the flow is faster than solver.max_speed = "
                f"{self.case.solver.max_speed:g} m/s allows for. Raise solver.max_speed if such "
                "speeds are real, or use a fixed time.dt."
            )
        if done:
            self.dt_range = [
                min(self.dt_range[0], report.dt_min),
                max(self.dt_range[1], report.dt_max),
            ]
        return AdaptiveReport(
            **vars(r), steps=done, dt_min=float(report.dt_min), dt_max=float(report.dt_max)
        )

    def owned_particles(self) -> ParticleArrays:
        """This rank's own particles (global coordinates, with their numbers ``id``, in
        their order in the run) between chunks (``parallel.snapshots``); collective."""
        self.parted()
        return self._distribute()

    def check_free_surface(self) -> None:
        """As ``ProjectionScheme.check_free_surface``, over the ranks."""
        O = self.options(1.0)
        if O.cell_pressure:  # a solid's surface is natural: no level to refer to
            return
        self._split()
        O.pockets = False
        self.exchange.start(self._distribute())
        _, x, v, mass, volume, p, affine, *_ = self.exchange.particles()
        core = self.core
        core.predict(x, v, mass, volume, p, O, False, affine=affine)
        core.pressure_matrix(O)
        owned = self.sub.owned_nodes[core.rows]
        n = self.comm.allreduce(int(owned.sum()))
        anchored = self.comm.allreduce(int(core.anchored[owned].any()))
        if n and not anchored:
            raise pressure.singular(" at the start")

    def state(self) -> dict[str, NDArray[Any]]:
        """As ``ProjectionScheme.state``, less the particles' own arrays
        (``particle_state``): what rank 0 writes into a checkpoint's main file."""
        saved = {
            "time": np.array(self.time),
            "p_node": self.p_global.copy(),
            "last_unknowns": np.array(self.last_unknowns),
            "steps": np.array(self.steps),
            "since_volume": np.array(self.since_volume),
            "dt_range": np.array(self.dt_range),
        }
        if self.q_global.size:
            saved["volume_q"] = self.q_global.copy()
        if self.pc_global.size:
            saved["p_cell"] = self.pc_global.copy()
        if self.movers:  # the free bodies' poses and velocities, as one process writes them
            if self.body_state is None:  # before the first chunk: the case's (collective)
                self.parted()
                self.body_state = self.core.body_state.copy()
            saved["body_state"] = self.body_state.copy()
        return saved

    def particle_state(self) -> dict[str, NDArray[Any]]:
        """This rank's part of the scheme's state carried by the particles: their numbers
        in the run (``id``), with APIC the affine matrices, a solid's history (one piece of
        a checkpoint). Collective (the particles are parted first)."""
        self.parted()
        assert self.ids is not None
        saved: dict[str, NDArray[Any]] = {"id": self.ids}
        if self.affine is not None:
            saved["affine"] = self.affine
        saved.update(self.history)
        return saved

    def restore(self, saved: dict[str, NDArray[Any]]) -> None:
        np.copyto(self.p_global, saved["p_node"])
        if self.q_global.size and "volume_q" in saved:  # written by one process, or ranks
            np.copyto(self.q_global, saved["volume_q"])
        self.last_unknowns = int(saved["last_unknowns"])
        self.steps = int(saved["steps"])
        if "time" in saved:  # checkpoints written before moving obstacles lack it
            self.time = float(saved["time"])
        if "since_volume" in saved:
            self.since_volume = float(saved["since_volume"])
            self.dt_range = [float(t) for t in saved["dt_range"]]
        if self.pc_global.size and "p_cell" in saved:
            np.copyto(self.pc_global, saved["p_cell"])
        if self.movers:
            self.body_state = np.ascontiguousarray(saved["body_state"], dtype=float)
        # the particles' own: this rank's part of a checkpoint in pieces (with their
        # numbers), or the whole run (every rank's the same, parted at the first split)
        if "id" in saved:
            self.adopt(saved["id"])
        if self.affine is not None:
            np.copyto(self.affine, saved["affine"])
        for name, a in self.history.items():
            np.copyto(a, saved[name])  # KeyError: a checkpoint of a fluid continued as a solid
