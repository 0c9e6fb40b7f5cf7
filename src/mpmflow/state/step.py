"""The compiled projection step: its state, options, report and statuses (src/core/step)."""

import enum

import numpy as np

from .. import _core
from . import arrays


class Status(enum.IntEnum):
    """How a step ended (``Report.status``; the core's ``Status``, src/core/step.hpp)."""

    OK = _core.OK
    SINGULAR = _core.SINGULAR
    PRESSURE_NOT_CONVERGED = _core.PRESSURE_NOT_CONVERGED
    VOLUME_NOT_CONVERGED = _core.VOLUME_NOT_CONVERGED
    VISCOUS_NOT_CONVERGED = _core.VISCOUS_NOT_CONVERGED
    INTERRUPTED = _core.INTERRUPTED  # a signal asked the chunk to stop between steps


OK = Status.OK
SURFACE_QUADRATURE = {
    "gauss": _core.GAUSS,
    "divergence": _core.DIVERGENCE,
    "consistent": _core.CONSISTENT,
}
Report = _core.Report


def step_state(grid, walls, solids, viscous_T, margin, volume_correction, viscous, outlets=()):
    """The compiled step's state for a grid (``mpmflow.grid.Grid``): ``walls`` = (node,
    axis, sign, no_slip) of the domain walls (``wall_pairs`` and a flag per pair), ``solids`` the obstacles' tables
    (``mpmflow.boundaries.obstacles.Tables``), ``viscous_T`` the full cell's gradient products (empty
    for inviscid material), ``margin`` (m) how far inside the walls particles are put back,
    ``outlets`` one flag per side (x_min, x_max, y_min, ...; empty: none): the open sides,
    which have no wall pairs and retire the particles that cross them (mass 0).
    The state keeps its own work arrays from step to step."""
    D = grid.dim
    cls = _core.State2 if D == 2 else _core.State3
    node, axis, sign, no_slip = walls
    o = solids
    return cls(
        float(grid.spacing),
        [int(c) for c in grid.cells],
        float(grid.cell_volume),
        [float(u) for u in grid.size],
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
    )


def step_options(dim, **settings):
    """The compiled step's settings (``Options2``/``Options3``) from keyword values."""
    opt = _core.Options2() if dim == 2 else _core.Options3()
    for key, value in settings.items():
        setattr(opt, key, value)
    return opt


PHASES = tuple(_core.PHASES)  # the phases a step's State times (``phase_seconds``)
