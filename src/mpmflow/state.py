"""The scheme's state and the one door to the compiled core (``mpmflow._core``).

Nothing else in mpmflow imports the core: the rest of the package calls the functions
here, which take NumPy arrays and grids and call the C++ kernels (src/core, one header/
source pair per concept). The core is built once, at install (scikit-build-core, CMake);
nothing compiles at run time.
"""

import numpy as np

from . import _core

CHUNKS = _core.CHUNKS


def max_threads():
    """The threads the core's parallel loops use."""
    return _core.max_threads()


def set_threads(n):
    """Run the core's parallel loops on n threads."""
    _core.set_threads(int(n))

POOL = _core.max_threads()  # the threads at import: OMP_NUM_THREADS, or the cores

# --- step ---
OK, SINGULAR = _core.OK, _core.SINGULAR
PRESSURE_NOT_CONVERGED = _core.PRESSURE_NOT_CONVERGED
VOLUME_NOT_CONVERGED = _core.VOLUME_NOT_CONVERGED
VISCOUS_NOT_CONVERGED = _core.VISCOUS_NOT_CONVERGED
SURFACE_QUADRATURE = {"gauss": _core.GAUSS, "divergence": _core.DIVERGENCE,
                      "consistent": _core.CONSISTENT}
Report = _core.Report


def _ints(a):
    return np.ascontiguousarray(a, dtype=np.int64)


def _floats(a):
    return np.ascontiguousarray(a, dtype=np.float64)


def step_state(grid, walls, solids, viscous_T, margin, volume_correction, viscous):
    """The compiled step's state for a grid (``mpmflow.grid.Grid``): ``walls`` = (node,
    axis, sign) of the domain walls, ``solids`` the obstacles' tables
    (``mpmflow.obstacles.Tables``), ``viscous_T`` the full cell's gradient products (empty
    for inviscid material), ``margin`` (m) how far inside the walls particles are put back.
    The state keeps its own work arrays from step to step."""
    D = grid.dim
    cls = _core.State2 if D == 2 else _core.State3
    node, axis, sign = walls
    o = solids
    return cls(float(grid.spacing), [int(c) for c in grid.cells], float(grid.cell_volume),
               [float(u) for u in grid.size], float(margin), _ints(node), _ints(axis),
               _ints(sign), _floats(o.phi), _floats(o.open), _ints(o.static_slot),
               _floats(o.K), _floats(o.C), _floats(o.V), _floats(o.F), _floats(o.Wf),
               _ints(o.node), _floats(np.reshape(o.normal, (-1, D))),
               np.ascontiguousarray(o.no_slip, dtype=np.bool_),
               _floats(np.reshape(viscous_T, (-1,) + (1,) * 3) if np.size(viscous_T) == 0
                       else viscous_T),
               bool(volume_correction), bool(viscous))


def step_options(dim, **settings):
    """The compiled step's settings (``Options2``/``Options3``) from keyword values."""
    opt = _core.Options2() if dim == 2 else _core.Options3()
    for key, value in settings.items():
        setattr(opt, key, value)
    return opt
