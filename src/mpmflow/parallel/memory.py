"""The memory of a run over N ranks, per rank, estimated from the case before anything is
allocated (issue 42, item 4).

The split is the one the run makes at its start (``boxes``: recursive bisection on the
particles per cell), found without the particles: a box-shaped body's particles per cell
are a product of one factor per axis (the lattice planes each cell holds along it), so the
bisection's profiles are sums of those factors (``boxes.bisect_separable``). For a box body
that no obstacle carves this is the run's split exactly; any other body (a sphere, a mesh,
a cosine top, particles left out round an obstacle) is taken as its bounding box's lattice
with the body's exact count spread evenly over it, and the estimate says so.

Each rank's peak is the sum of these terms (bytes):

- the program: Python, NumPy, SciPy, the core, mpi4py, and PETSc with hypre (measured);
- the seeding (``parallel.seeding``): a chunk of the bodies' lattice (``lattice.CHUNK``
  points, or the whole run's when it is smaller) and the cells' counts that the ranks'
  split comes from; no rank holds the whole run;
- the whole grid's arrays every rank keeps (the nodal pressure, the cells' tables);
- this rank's own particles and its halo (the neighbours' particles in its ghost layer):
  their copies in the step, the core's arrays, the migration's;
- the local grid (the box and its ghost layer): the core's node and cell arrays, the
  exchange's index tables;
- the pressure system of its owned unknowns: the core's rows, PETSc's matrix and hypre's
  BoomerAMG hierarchy;
- the time series kept in memory, as one process keeps them;
- the measures at an output time: sums over the whole grid's cells and nodes, added up
  over the ranks (``diagnostics.parts``); no rank gathers the particles (snapshots and
  checkpoints are written in one piece a rank).

The bytes per particle, node and unknown were measured with
``benchmarks/investigations/mpi/memory_ranks.py`` on the 3D dam break (0.004 and 0.003 m,
2 and 4 ranks; numbers in docs/notes/benchmarks-diary.md, "Memory per rank"). On one rank a
run is a one-process run and its estimate is ``mpmflow.memory.estimate``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from .. import memory
from ..boundaries import moving
from ..errors import CaseError
from ..geometry import bodies
from ..geometry.lattice import CHUNK, lattice_indices
from ..grid import Grid
from ..materials import is_solid
from .boxes import Boxes, Factors, bisect_separable, box_weight
from .comm import ranks_here, world
from .subgrid import ghost_layers

if TYPE_CHECKING:
    from ..case import Case

MB = memory.MB
# measured (benchmarks/investigations/mpi/memory_ranks.py): see the module docstring.
# Per particle in copies of its fields (particle_fields: 72 B in 3D, 56 B in 2D; with APIC
# its affine matrix rides in every copy). By dimension: a 3D cell holds 8 particles of the
# examples and a 2D one 16, so the grid's share per particle differs; fitted on the dam
# breaks' ranks (3D: 12 rank-runs, 2D: 4) with PETSc's bytes held at their measured value
PROGRAM = 128 * MB  # Python, NumPy, SciPy, the core, mpi4py, PETSc and hypre loaded
WHOLE_PER_NODE = 24  # B per node of the whole grid: nodal pressure, the cells' tables
LOCAL_COPIES = {2: 5.5, 3: 9.6}  # per owned or halo particle: step copies, core, migration
LOCAL_PER_NODE = {2: 120, 3: 180}  # B per node of the local grid: core arrays, index tables
PETSC_PER_UNKNOWN = {2: 400, 3: 1950}  # B: PETSc's AIJ and BoomerAMG, measured per rank
# B per node at an output time: the measures' sums over the whole grid (theta on the cells,
# the pressure noise's two nodal sums), each summed over the ranks in place (counted: 3
# arrays x 8 B; mpi4py's pickled all-reduce, before, held 3 to 4 times each array at its
# peak on 2 and 4 ranks, measured with tracemalloc)
MEASURES_PER_NODE = 24
# B per cell while seeding: the cells' counts, one chunk's and their running sum (int64),
# with the sum's new array (counted)
SEEDING_PER_CELL = 24
# the most cells per axis whose factors the split makes (8 B each): 10^8 is 800 MB
MAX_CELLS_PER_AXIS = 10**7


def particle_fields(dim: int, apic: bool, solid: bool = False) -> int:
    """Bytes of one particle's fields in a run's particle set: x, v (D each), pressure,
    mass, volume, with APIC its D x D affine matrix, and a solid's history (its D x D
    deviatoric stress, plastic strain and yielding flag), which ride in every copy too."""
    history = 8 * (dim * dim + 2) if solid else 0
    return 8 * (2 * dim + 3) + (8 * dim * dim if apic else 0) + history


@dataclass
class RankEstimate:
    """One rank's estimated peak (bytes per term) and the counts it comes from."""

    rank: int
    particles: float  # this rank's own particles at the start
    halo: float  # the neighbours' particles in its ghost layer
    local_nodes: float  # nodes of its box with the ghost layer
    unknowns: float  # its owned pressure unknowns, with room for the material to spread
    terms: dict[str, float]  # name -> bytes, in the order they are told

    @property
    def total(self) -> float:
        return float(sum(self.terms.values()))

    def text(self) -> str:
        parts = ", ".join(f"{name} {memory.size(b)}" for name, b in self.terms.items())
        return f"about {memory.size(self.total)} ({parts})"

    def as_dict(self) -> dict[str, object]:
        return {
            "rank": self.rank,
            "total": self.total,
            "terms": dict(self.terms),
            "counts": {
                "particles": self.particles,
                "halo": self.halo,
                "local_nodes": self.local_nodes,
                "unknowns": self.unknowns,
            },
        }


@dataclass
class RanksEstimate:
    """The estimate of every rank of a run on ``ranks`` processes."""

    ranks: int
    particles: float  # the run's particles
    nodes: float  # the whole grid's
    boxes: Boxes
    per_rank: list[RankEstimate]
    approximate: list[str]  # why the split is approximate (empty: the run's own)
    here: int  # the ranks on this machine (they share its memory)

    @property
    def largest(self) -> RankEstimate:
        return max(self.per_rank, key=lambda r: r.total)

    @property
    def total(self) -> float:
        """All ranks together."""
        return float(sum(r.total for r in self.per_rank))

    def lines(self, every: int = 8) -> list[str]:
        """What the estimate says, for people: the largest rank's terms, the range, and
        each rank's total when there are at most ``every`` ranks."""
        big = self.largest
        low = min(r.total for r in self.per_rank)
        out = [
            f"memory per rank on {self.ranks} ranks: largest rank {big.rank}: {big.text()}; "
            f"ranks from {memory.size(low)} to {memory.size(big.total)}, "
            f"{memory.size(self.total)} in all"
        ]
        if self.ranks <= every:
            out.append(
                "memory of each rank: "
                + ", ".join(
                    f"{r.rank}: {memory.size(r.total)} ({r.particles:,.0f} particles, "
                    f"{r.halo:,.0f} halo, {r.local_nodes:,.0f} nodes, "
                    f"{r.unknowns:,.0f} unknowns)"
                    for r in self.per_rank
                )
            )
        if self.approximate:
            out.append("the split is approximate: " + "; ".join(self.approximate))
        return out

    def as_dict(self) -> dict[str, object]:
        return {
            "ranks": self.ranks,
            "largest": self.largest.rank,
            "total": self.total,
            "per_rank": [r.as_dict() for r in self.per_rank],
            "boxes": {"lo": self.boxes.lo.tolist(), "hi": self.boxes.hi.tolist()},
            "approximate": list(self.approximate),
        }


def _axis_factor(a: float, b: float, s: float, h: float, cells: int) -> np.ndarray:
    """The lattice planes (spacing s) in [a, b) that fall in each of the cells (size h)
    along one axis, as the core bins them (beyond the grid: the nearest cell)."""
    k0, k1 = lattice_indices(a, b, s)
    if k1 < k0:
        return np.zeros(cells)
    x = (np.arange(k0, k1 + 1) + 0.5) * s
    ijk = np.clip(np.floor(x / h).astype(np.int64), 0, cells - 1)
    return np.bincount(ijk, minlength=cells).astype(float)


def layers(case: Case, grid: Grid) -> tuple[list[Factors], list[str]]:
    """The particles per cell as a sum of products of one factor per axis (one layer a
    body), and why that is approximate (empty: exact)."""
    h = grid.spacing
    counts = case.particle_counts()
    out: list[Factors] = []
    why: list[str] = []
    for k, body in enumerate(case.bodies):
        s = h / body.particles_per_cell
        lo, hi = bodies.seed_region(body, case.body_shape(k), s)
        factors = tuple(
            _axis_factor(float(a), float(b), s, h, int(c)) for a, b, c in zip(lo, hi, grid.cells)
        )
        seeded = math.prod(float(f.sum()) for f in factors)
        if seeded > 0 and counts[k] != seeded:  # not a plain box: its count spread evenly
            factors = (factors[0] * (float(counts[k]) / seeded), *factors[1:])
            shape = getattr(body, "type", "box")
            kind = "a box with a cosine top or obstacles in it" if shape == "box" else shape
            why.append(
                f"body {k} ({kind}) is taken as its bounding box's lattice holding its "
                f"{counts[k]:,.0f} particles evenly"
            )
        out.append(factors)
    return out, why


def _owned_node_range(lo: int, hi: int, cells: int) -> tuple[int, int]:
    """Node indices [a, b) owned along one axis by a box of cells [lo, hi): the nodes whose
    lower cell it holds, and the last node plane when the box ends at the grid's side."""
    return lo, hi + (1 if hi == cells else 0)


def _unknowns(layer: Factors, lo: np.ndarray, hi: np.ndarray, cells: tuple[int, ...]) -> float:
    """The nodes of a layer's cells (those holding particles) that a box owns."""
    n = 1.0
    for f, a, b, c in zip(layer, lo, hi, cells):
        full = np.flatnonzero(f)
        if full.size == 0:
            return 0.0
        first, last = int(full[0]), int(full[-1]) + 1  # the cells' nodes: [first, last]
        own_a, own_b = _owned_node_range(int(a), int(b), c)
        n *= max(0, min(last + 1, own_b) - max(first, own_a))
    return n


def estimate(case: Case, ranks: int) -> RanksEstimate:
    """The estimate of each rank of a run of ``case`` on ``ranks`` processes (no
    particles are made: counts from the geometry). CaseError when the split cannot be
    made (more ranks than cells, a grid too fine to split here)."""
    if ranks < 1:
        raise CaseError(f"--ranks {ranks}: give a number of processes of 1 or more.")
    grid = Grid.covering(case.domain.size, case.grid.spacing)
    cells = tuple(int(c) for c in grid.cells)
    if max(cells) > MAX_CELLS_PER_AXIS:
        raise CaseError(
            f"grid.spacing = {case.grid.spacing:g} m gives {max(cells):.3g} cells along an "
            f"axis, more than the split can be found for ({MAX_CELLS_PER_AXIS:.0e}): no "
            "machine holds such a case. Make grid.spacing larger."
        )
    D = grid.dim
    one = memory.estimate(case)
    N = float(one.particles)
    nodes = float(one.nodes)
    factors, why = layers(case, grid)
    try:
        boxes = bisect_separable(factors, cells, ranks)
    except ValueError as err:
        raise CaseError(f"--ranks {ranks}: {err}; run on fewer ranks.") from None
    apic = case.solver.transfer == "apic"
    fields = particle_fields(D, apic, is_solid(case.material))
    ghost = ghost_layers(any(m is not None for m in moving.motions(case)))
    seeding = min(N, float(CHUNK)) * fields + SEEDING_PER_CELL * math.prod(cells)
    grid_whole = WHOLE_PER_NODE * nodes
    measures = MEASURES_PER_NODE * nodes
    local = LOCAL_COPIES[D] * fields
    per_rank = []
    for r in range(ranks):
        lo, hi = boxes.lo[r], boxes.hi[r]
        elo = np.maximum(lo - ghost, 0)
        ehi = np.minimum(hi + ghost, np.asarray(cells))
        own = box_weight(factors, lo, hi)
        halo = box_weight(factors, elo, ehi) - own
        local_nodes = float(np.prod([float(b - a + 1) for a, b in zip(elo, ehi)]))
        owned = [_owned_node_range(int(a), int(b), c) for a, b, c in zip(lo, hi, cells)]
        owned_nodes = float(np.prod([float(b - a) for a, b in owned]))
        seeded = sum(_unknowns(f, lo, hi, cells) for f in factors)
        unknowns = min(owned_nodes, memory.SPREAD * seeded)
        terms = {
            "program": float(PROGRAM),
            "seeding (a chunk of the lattice)": seeding,
            "the whole grid's arrays": grid_whole,
            "own particles": local * own,
            "halo": local * halo,
            "local grid (box and ghost layer)": LOCAL_PER_NODE[D] * local_nodes,
            "pressure system (PETSc, hypre)": PETSC_PER_UNKNOWN[D] * unknowns,
            "time series": float(one.rows_bytes),
            "the measures at an output time": measures,
        }
        per_rank.append(RankEstimate(r, own, halo, local_nodes, unknowns, terms))
    return RanksEstimate(ranks, N, nodes, boxes, per_rank, why, min(ranks_here(), ranks))


def check(case: Case, ranks: int) -> RanksEstimate:
    """The estimate of each rank; CaseError when the ranks this machine holds need more
    than it can give (``memory.available``)."""
    est = estimate(case, ranks)
    budget, source = memory.available()
    big = est.largest
    need = est.here * big.total
    # every rank decides together: the ranks read the free memory at different moments,
    # and one refusing alone would leave the others waiting in the scheme's first exchange
    if world().allreduce(int(need > budget)) == 0:
        return est
    power = {2: "square", 3: "cube"}[len(case.domain.size)]
    raise CaseError(
        f"This case needs {big.text()} on its largest rank ({big.rank} of {ranks}); the "
        f"{est.here} ranks on this machine need {memory.size(need)}, and it can give "
        f"{memory.size(budget)} ({source}), so they would be killed by the system when it "
        f"runs out. Every rank holds the whole grid's arrays, so more ranks on one machine "
        f"need more, not less: make the case smaller (grid.spacing: memory grows "
        f"as its inverse {power}; bodies.N.particles_per_cell), start fewer ranks on each "
        "machine, or run on machines with more memory. `mpmflow run CASE --dry-run --ranks "
        "N` prints each rank's estimate without running. (MPMFLOW_MEMORY_LIMIT sets the "
        "memory a run may use, if the available memory is measured wrong here.)"
    )
