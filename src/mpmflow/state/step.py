"""The compiled projection step: its state, options, report and statuses (src/core/step)."""

from __future__ import annotations

import enum
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np

from .. import _core, arrays
from ..arrays import Bools, Floats, Ints
from ..grid import Grid

if TYPE_CHECKING:  # obstacles builds its tables with this package's kernels
    from ..boundaries.obstacles import Tables


class Status(enum.IntEnum):
    """How a step ended (``Report.status``; the core's ``Status``, src/core/step.hpp)."""

    OK = _core.OK
    SINGULAR = _core.SINGULAR
    PRESSURE_NOT_CONVERGED = _core.PRESSURE_NOT_CONVERGED
    VOLUME_NOT_CONVERGED = _core.VOLUME_NOT_CONVERGED
    VISCOUS_NOT_CONVERGED = _core.VISCOUS_NOT_CONVERGED
    INTERRUPTED = _core.INTERRUPTED  # a signal asked the chunk to stop between steps
    # the coupled step's plastic iterations did not settle (State::plastic_solve)
    PLASTIC_NOT_CONVERGED = _core.PLASTIC_NOT_CONVERGED


OK = Status.OK
SURFACE_QUADRATURE: dict[str, int] = {
    "gauss": _core.GAUSS,
    "divergence": _core.DIVERGENCE,
    "consistent": _core.CONSISTENT,
}


# The core's classes have no type information (a compiled module without stubs): the
# Protocols below say what Python reads and calls of them (src/core/bindings/step.cpp).


class CoreReport(Protocol):
    """What a chunk of compiled steps did (the core's ``Report``, src/core/step.hpp)."""

    unknowns: int  # the largest number of pressure unknowns in a step
    solves: int
    iterations: int
    max_iterations: int  # the most iterations in one step
    residual: float  # the worst relative residual
    released: int
    unsettled: int  # steps whose walls' contact had not settled (complementarity.hpp)
    plastic_iterations: int  # the coupled step's plastic iterations (State::plastic_solve)
    moved: int
    status: int  # a ``Status``
    step: int  # the step (0-based, within the chunk) that failed or is running
    fail_iterations: int
    fail_residual: float
    fail_node: int  # node (pressure, viscous) or cell (volume correction)
    fail_size: int  # unknowns of the failed system
    volume_iterations: int
    last_unknowns: int  # the unknowns of the last step
    viscous_iterations: int
    steps: int  # the steps taken
    dt_min: float  # the shortest and longest step taken (s)
    dt_max: float
    capped: int
    clamped: int
    pockets: int


Report: Callable[[], CoreReport] = _core.Report  # a zeroed report


class CoreOptions(Protocol):
    """The compiled step's settings (``Options2``/``Options3``, src/core/step.hpp)."""

    dt: float
    gravity: list[float]
    rho: float
    flip: float
    full: float
    sparse: float
    partial_particles: bool
    cell_pressure: bool  # a solid's pressure per cell (src/core/cell_pressure.hpp)
    coupled: bool  # a solid's elastic solve and projection as one system (State::coupled_solve)
    surface: int
    subcell: bool
    wall_flux: bool
    # pressure_matrix holds the sealed pockets at 0 at their top; False leaves them (0
    # pockets), for a caller owning part of the domain that decides them across the parts
    pockets: bool
    theta_min: float
    # sub-cell surface: unknowns nearer the surface than this fraction of an edge are
    # interpolated instead (src/core/ghost_pressure.hpp, demote_shallow), at steps shorter
    # than shallow_max_dt (s)
    shallow: float
    shallow_max_dt: float
    expansion: float
    tol: float
    max_iterations: int
    sweeps: int
    volume_rate: float
    volume_every: int
    volume_tol: float
    volume_max_iterations: int
    volume_dmax: float
    viscous: bool
    model: int
    model_params: list[float]
    courant: float
    dt_max: float
    flip_rate: float
    volume_interval: float


class CoreState(Protocol):
    """The compiled projection step's state (``State2``/``State3``): its methods take the
    particles' arrays (x, v, pressure written in place; ``affine``: APIC's matrices, None:
    FLIP/PIC; ``stress``, ``plastic_strain``, ``yielding``: a solid's history, None: a
    fluid) and the step's options; the arrays it exposes are views of its own storage."""

    since_volume: float  # the time since the last volume correction (s)
    inlet_travel: Floats  # where each inlet row's next particle is (m; src/core/inlets.hpp)
    inlet_next: int  # the first particle of the inlets' pool not emitted yet
    time: float  # the flow time (s); setting it places the moving obstacles
    plate_velocity: float  # a plate's velocity along its axis (m/s; State::set_plate)
    body_force: Floats  # (bodies, D) the material's force on each moving obstacle (N; 2D N/m)
    body_torque: Floats  # (bodies, 3) its torque about the pivot (N m; 2D N m/m)
    # (bodies, 13) pivot, velocity, angular velocity, orientation quaternion (settable)
    body_state: Floats

    def set_inlet_pool(self, first: int, end: int) -> None: ...

    def set_plate(self, axis: int, side: int, force: float) -> None: ...

    def set_bodies(self, bodies: list[dict[str, Any]], fixed_no_slip: Bools, nsub: int) -> None: ...

    def advance(
        self,
        x: Floats,
        v: Floats,
        mass: Floats,
        volume: Floats,
        pressure: Floats,
        options: CoreOptions,
        first: int,
        nsteps: int,
        report: CoreReport,
        affine: Floats | None = None,
        stress: Floats | None = None,
        plastic_strain: Floats | None = None,
        yielding: Floats | None = None,
    ) -> int:
        """nsteps steps; returns the steps done (fewer: report.status says why)."""
        ...

    def advance_span(
        self,
        x: Floats,
        v: Floats,
        mass: Floats,
        volume: Floats,
        pressure: Floats,
        options: CoreOptions,
        span: float,
        max_steps: int,
        report: CoreReport,
        affine: Floats | None = None,
        stress: Floats | None = None,
        plastic_strain: Floats | None = None,
        yielding: Floats | None = None,
    ) -> float:
        """Adaptive steps over the span (s); returns the time covered."""
        ...

    def predict(
        self,
        x: Floats,
        v: Floats,
        mass: Floats,
        volume: Floats,
        pressure: Floats,
        options: CoreOptions,
        correct: bool,
        affine: Floats | None = None,
        stress: Floats | None = None,
        plastic_strain: Floats | None = None,
        yielding: Floats | None = None,
    ) -> int:
        """The step up to the pressure system (scatter, then classify); returns the
        pressure unknowns."""
        ...

    def scatter(
        self,
        x: Floats,
        v: Floats,
        mass: Floats,
        volume: Floats,
        pressure: Floats,
        options: CoreOptions,
        correct: bool,
        affine: Floats | None = None,
        stress: Floats | None = None,
        plastic_strain: Floats | None = None,
        yielding: Floats | None = None,
    ) -> None:
        """The particles to the grid: binning (theta), node_mass, node_vol, v_old, v_star
        (and cell_vol when correct), v_star into the obstacles, node_f."""
        ...

    def classify(
        self,
        x: Floats,
        v: Floats,
        mass: Floats,
        volume: Floats,
        pressure: Floats,
        options: CoreOptions,
    ) -> int:
        """The enclosed cells, the cells' integrals and the unknowns (node_row, rows) from
        scatter's arrays, for the particles scatter was given (ValueError otherwise); returns
        the pressure unknowns."""
        ...

    def renumber(self) -> int:
        """The rows again from node_row (>= 0: an unknown, -1: not) in classify's order
        (an image node of a periodic axis shares its master's row); returns the unknowns."""
        ...

    def use_solvers(self, pressure: Any = None, volume: Any = None, viscous: Any = None) -> None:
        """The systems' solvers from Python (None: the core's multigrid): pressure and volume
        with ``setup(cols, vals, rows)`` and ``solve(rhs, x) -> (iterations, residual)``,
        viscous with ``solve(x) -> (iterations, residual)``."""
        ...

    def use_exchange(
        self, exchange: Any, owned_nodes: Bools | None = None, owned_cells: Bools | None = None
    ) -> None:
        """Where the step meets the other ranks (src/core/exchange.hpp; None: one process)."""
        ...

    def pressure_solve(self, options: CoreOptions, report: CoreReport) -> int:
        """The pressure step after predict; returns a ``Status``."""
        ...

    def warm_start(self) -> None: ...

    def pressure_matrix(self, options: CoreOptions) -> bool:
        """Assemble; False: singular (no free surface)."""
        ...

    def pressure_rhs(self, options: CoreOptions) -> None: ...

    def extend_pressure(self, options: CoreOptions) -> None: ...

    def viscous_predictor(self, options: CoreOptions, report: CoreReport) -> int:
        """Returns a ``Status``."""
        ...

    def viscous_start(self, options: CoreOptions, report: CoreReport) -> None:
        """The viscous predictor's start: the walls' contact, eta, ``viscous_base``."""
        ...

    def viscous_system(self, options: CoreOptions) -> int:
        """The viscous predictor's system from ``viscous_base``, not solved
        (``viscous_*``); returns its unknowns."""
        ...

    def viscous_apply(self, x: Floats) -> None:
        """x (one value per unknown of the last viscous_system, m/s) into v_star."""
        ...

    def finish(
        self,
        x: Floats,
        v: Floats,
        mass: Floats,
        volume: Floats,
        pressure: Floats,
        options: CoreOptions,
        correct: bool,
        report: CoreReport,
        affine: Floats | None = None,
        stress: Floats | None = None,
        plastic_strain: Floats | None = None,
        yielding: Floats | None = None,
    ) -> int:
        """The step after the pressure solve (correct, the volume correction when
        correct, to_particles); returns a ``Status``."""
        ...

    def correct(self, options: CoreOptions) -> None:
        """v_new: the corrected velocity with the walls' and obstacles' conditions."""
        ...

    def volume_system(self, options: CoreOptions) -> int:
        """The volume correction's cell-centred system from cell_vol (a scatter with
        correct) and the pressure step's wall contact: ``volume_rows``, ``volume_cols``,
        ``volume_vals``, ``volume_rhs``, ``volume_air``, ``volume_anchored``, ``cell_row``;
        its sealed pockets made solvable when ``options.pockets`` and it is anchored (False
        leaves them to a caller owning part of the domain). Returns the rows.
        RuntimeError on a state built without the volume correction."""
        ...

    def volume_apply(self, options: CoreOptions, q: Floats) -> int:
        """q (one value per row of the last ``volume_system``, ValueError otherwise) into
        ``volume_q`` and the faces' displacements ``to_particles(displaced=True)`` adds;
        zero faces, q ignored, when that system had no rows or was not anchored. Returns the
        faces clamped at ``options.volume_dmax`` cells (``Report.clamped``)."""
        ...

    def to_particles(
        self,
        x: Floats,
        v: Floats,
        mass: Floats,
        volume: Floats,
        pressure: Floats,
        options: CoreOptions,
        displaced: bool,
        affine: Floats | None = None,
        stress: Floats | None = None,
        plastic_strain: Floats | None = None,
        yielding: Floats | None = None,
    ) -> int:
        """Grid to particles (with the volume correction's displacements when displaced),
        push-out of obstacles, the periodic wrap; the particles may be the first n of those
        scatter was given. Returns the particles put back inside."""
        ...

    @property
    def pockets(self) -> int: ...
    @property
    def phase_seconds(self) -> list[float]: ...
    @property
    def p_node(self) -> Floats: ...
    @property
    def p_cell(self) -> Floats: ...  # a solid's pressure per cell (Pa; cell_pressure.hpp)
    @property
    def v_new(self) -> Floats: ...
    @property
    def contact(self) -> Bools: ...
    @property
    def eta(self) -> Floats: ...
    @property
    def ocontact(self) -> Bools: ...
    @property
    def volume_q(self) -> Floats: ...
    @property
    def rows(self) -> Ints: ...
    # scatter's and classify's arrays (views: a caller may write them between the phases)
    @property
    def node_mass(self) -> Floats: ...
    @property
    def node_vol(self) -> Floats: ...
    @property
    def v_old(self) -> Floats: ...
    @property
    def v_star(self) -> Floats: ...
    @property
    def node_f(self) -> Floats: ...
    @property
    def node_row(self) -> Ints: ...
    @property
    def theta(self) -> Floats: ...
    @property
    def cell_vol(self) -> Floats: ...  # empty without the volume correction
    @property
    def anchored(self) -> Bools: ...  # the rows next to a free surface (pressure_matrix)
    @property
    def matrix_cols(self) -> Ints: ...
    @property
    def matrix_vals(self) -> Floats: ...
    @property
    def rhs(self) -> Floats: ...
    @property
    def x0(self) -> Floats: ...
    # the last volume_system's cell-centred system (empty before one and without the
    # volume correction): the cell of each row (n), the ELL matrix (n x 3^D, -1: no column),
    # the right-hand side (a view: writable), the rows that touch an empty cell (their values
    # sum to more than 0.5), whether any does; each cell's row (ncells, -1: none)
    @property
    def volume_rows(self) -> Ints: ...
    @property
    def volume_cols(self) -> Ints: ...
    @property
    def volume_vals(self) -> Floats: ...
    @property
    def volume_rhs(self) -> Floats: ...
    @property
    def volume_air(self) -> Bools: ...

    # whether the volume system touches an empty cell; set by an MPI caller for the whole
    volume_anchored: bool

    @property
    def cell_row(self) -> Ints: ...

    # the last viscous_start's velocity the solve starts from (v* corrected by the last
    # pressure) and the last viscous_system (empty without a viscous material): each node's
    # row per component (nn x D, -1: held or massless), each component's first row (D + 1),
    # the blocks (D x n x 3^D: the couplings of each row to component m, columns numbered
    # within component m, -1 empty), the right-hand side and the start (n, writable)
    @property
    def viscous_rows(self) -> Ints: ...
    @property
    def viscous_off(self) -> Ints: ...
    @property
    def viscous_cols(self) -> Ints: ...
    @property
    def viscous_vals(self) -> Floats: ...
    @property
    def viscous_rhs(self) -> Floats: ...
    @property
    def viscous_x(self) -> Floats: ...
    @property
    def viscous_base(self) -> Floats: ...  # nn x D (m/s), writable


def adaptive_dt(vmax2: float, courant: float, h: float, dt_max: float, rest: float) -> float:
    """The adaptive step's size (s): min(dt_max, courant h / |v|max), fitted to the rest of
    the span (the core's rule, src/core/step.hpp; every loop that takes steps uses it)."""
    return float(_core.adaptive_dt(vmax2, courant, h, dt_max, rest))


def volume_due_fixed(number: int, every: int) -> bool:
    """Fixed steps: the volume correction on step ``number`` (from 1)? (the core's rule)"""
    return bool(_core.volume_due_fixed(number, every))


def volume_due_adaptive(
    since: float, dt: float, rate: float, interval: float
) -> tuple[bool, float]:
    """Adaptive steps: (the volume correction due?, the flow time since it after this step)
    (the core's rule)."""
    due, since = _core.volume_due_adaptive(since, dt, rate, interval)
    return bool(due), float(since)


def step_state(
    grid: Grid,
    walls: tuple[Ints, Ints, Floats, Bools],
    solids: Tables,
    viscous_T: Floats,
    margin: float,
    volume_correction: bool,
    viscous: bool,
    outlets: Sequence[bool] | Bools = (),
    lower: Sequence[float] | Floats | None = None,
    upper: Sequence[float] | Floats | None = None,
    bonded: Bools | None = None,
    held: Floats | None = None,
    inlets: Sequence[Floats | Ints] | None = None,
    damping: Floats | None = None,
    load: Floats | None = None,
) -> CoreState:
    """The compiled step's state for a grid (``mpmflow.grid.Grid``): ``walls`` = (node,
    axis, sign, no_slip) of the domain walls (``wall_pairs`` and a flag per pair), ``solids`` the obstacles' tables
    (``mpmflow.boundaries.obstacles.Tables``), ``viscous_T`` the full cell's gradient products (empty
    for inviscid material), ``margin`` (m) how far inside the walls particles are put back,
    ``outlets`` one flag per side (x_min, x_max, y_min, ...; empty: none): the open sides,
    which have no wall pairs and retire the particles that cross them (mass 0), ``lower``
    the domain's lower corner in the grid's coordinates (m; None: zeros), below which
    particles are put back inside: 0 for a grid on the whole domain, the global domain's
    corner for a grid on a part of it; ``upper`` likewise the upper corner (None: the
    grid's extent); ``bonded`` one flag per wall pair, the pairs held in tension too (None:
    none); ``held`` (nnodes x D, m/s; None: every wall at rest) the velocity each wall node
    is held to where its wall holds the material (an inlet's inflow); ``inlets`` the inlets'
    tables (axis, direction, speed, first, layer, spacing, mass, volume:
    ``boundaries.inlets.Tables.core``; None: none); ``damping`` each node's damping rate
    (1/s, ``boundaries.sponges.rates``; None: no damping zone); ``load`` each node's share of
    the surface loads (nnodes x D, N; 2D N/m; ``boundaries.loads.nodal``; None: none).
    The state keeps its own work arrays from step to step."""
    D = grid.dim
    cls: Callable[..., CoreState] = _core.State2 if D == 2 else _core.State3
    node, axis, sign, no_slip = walls
    o = solids
    return cls(
        float(grid.spacing),
        [int(c) for c in grid.cells],
        float(grid.cell_volume),
        [0.0] * D if lower is None else [float(c) for c in lower],
        [float(u) for u in (grid.size if upper is None else upper)],
        float(margin),
        arrays.ints(node),
        arrays.ints(axis),
        arrays.floats(sign),
        arrays.pair_flags(no_slip, node),
        arrays.floats(o.phi),
        arrays.floats(o.open),
        arrays.ints(o.static_slot),
        arrays.floats(o.K),
        arrays.floats(o.C),
        arrays.floats(o.V),
        arrays.floats(o.F),
        arrays.floats(o.Wf),
        arrays.ints(o.node),
        arrays.floats(np.reshape(o.normal, (-1, D))),
        np.ascontiguousarray(o.no_slip, dtype=np.bool_),
        arrays.floats(viscous_T),
        bool(volume_correction),
        bool(viscous),
        [bool(p) for p in grid.periodic],
        [bool(s) for s in outlets],
        np.ascontiguousarray(np.zeros(0) if bonded is None else bonded, dtype=np.bool_),
        arrays.floats(np.zeros((0, D)) if held is None else held),
        *_inlet_tables(D, inlets),
        arrays.floats(np.zeros(0) if damping is None else damping),
        arrays.floats(np.zeros((0, D)) if load is None else load),
    )


def _inlet_tables(D: int, inlets: Sequence[Floats | Ints] | None) -> list[Floats | Ints]:
    """The inlets' arrays in the core's types (empty ones for none)."""
    if inlets is None:
        empty = np.zeros(0)
        inlets = (empty, empty, empty, np.zeros(1), np.zeros((0, D)), empty, empty, empty)
    axis, direction, speed, first, layer, spacing, mass, volume = inlets
    return [
        arrays.ints(axis),
        arrays.floats(direction),
        arrays.floats(speed),
        arrays.ints(first),
        arrays.floats(layer),
        arrays.floats(spacing),
        arrays.floats(mass),
        arrays.floats(volume),
    ]


def step_options(dim: int, **settings: float | bool | list[float]) -> CoreOptions:
    """The compiled step's settings (``Options2``/``Options3``) from keyword values (the
    names of ``CoreOptions``)."""
    opt: CoreOptions = _core.Options2() if dim == 2 else _core.Options3()
    for key, value in settings.items():
        setattr(opt, key, value)
    return opt


PHASES: tuple[str, ...] = tuple(_core.PHASES)  # the phases a step's State times (``phase_seconds``)
