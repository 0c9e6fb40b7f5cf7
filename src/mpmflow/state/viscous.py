"""The viscous materials' kernels: effective viscosity, the implicit viscous system and
its solve (src/core/rheology.hpp, viscous)."""

from collections.abc import Sequence
from typing import TypeVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .. import _core, arrays
from ..arrays import Bools, Floats, Ints

_Scalar = TypeVar("_Scalar", bound=np.generic)

# the rheology's model codes (``mpmflow.materials``) and the implicit viscous predictor
# (src/core/rheology.hpp, src/core/viscous.hpp)
WATER: int = _core.WATER
NEWTONIAN: int = _core.NEWTONIAN
HERSCHEL_BULKLEY: int = _core.HERSCHEL_BULKLEY
MU_I: int = _core.MU_I
# the solids' codes (src/core/plasticity.hpp) and one particle's stress step
ELASTIC: int = _core.ELASTIC
VON_MISES: int = _core.VON_MISES
DRUCKER_PRAGER: int = _core.DRUCKER_PRAGER
POROELASTIC: int = _core.POROELASTIC
update_stress = _core.update_stress


def viscosity(model: int, par: ArrayLike, rate: float, p: float) -> float:
    """The effective viscosity (Pa s) of rheology ``model`` with parameters ``par`` at strain
    rate ``rate`` (1/s) and pressure ``p`` (Pa)."""
    return float(
        _core.viscosity(int(model), np.ascontiguousarray(par, dtype=float), float(rate), float(p))
    )


def _viscous_out(a: NDArray[_Scalar]) -> NDArray[_Scalar]:
    """``a`` itself when C-contiguous (the core writes into it), else a C-contiguous copy to
    be copied back with ``_viscous_back``."""
    return a if a.flags.c_contiguous else np.ascontiguousarray(a)


def _viscous_back(a: NDArray[_Scalar], c: NDArray[_Scalar]) -> None:
    if c is not a:
        a[...] = c


def gauss_gradients(cells: Sequence[int], h: float) -> Floats:
    """T[a, b, m, k] = int over a full cell of dN_a/dx_m dN_b/dx_k (2^D x 2^D x D x D)."""
    D = len(cells)
    T = np.empty((1 << D, 1 << D, D, D))
    _core.gauss_gradients([int(c) for c in cells], float(h), T)
    return T


def cell_viscosity(
    cells: Sequence[int],
    h: float,
    theta: Floats,
    open_: Floats,
    enclosed: Bools,
    full: float,
    v: Floats,
    p_node: Floats,
    model: int,
    par: ArrayLike,
    eta: Floats,
    weight: Floats,
) -> None:
    """Each cell's viscosity ``eta`` and ``weight`` = eta x its fluid fraction (in place)."""
    etac, weightc = _viscous_out(eta), _viscous_out(weight)
    _core.cell_viscosity(
        [int(c) for c in cells],
        float(h),
        theta,
        open_,
        enclosed,
        float(full),
        v,
        p_node,
        int(model),
        np.ascontiguousarray(par, dtype=float),
        etac,
        weightc,
    )
    _viscous_back(eta, etac)
    _viscous_back(weight, weightc)


def number_unknowns(
    node_mass: Floats,
    wall_node: Ints,
    wall_axis: Ints,
    wall_no_slip: ArrayLike,
    contact: Bools,
    onode: Ints,
    ocontact: Bools,
    ono_slip: Bools,
    vstar: Floats,
    u: Floats,
    row: Ints,
    off: Ints,
) -> int:
    """Number the viscous system's unknowns (``u``, ``row``, ``off`` in place); returns
    their count. ``wall_no_slip``: a flag per wall pair (or one bool for all); ``contact``
    (nodes x D) and ``ocontact`` (nodes) say where the walls and obstacles hold the material
    (the pressure step's starting contact)."""
    uc, rowc = _viscous_out(u), _viscous_out(row)
    n = _core.number_unknowns(
        node_mass,
        wall_node,
        wall_axis,
        arrays.pair_flags(wall_no_slip, wall_node),
        contact,
        onode,
        ocontact,
        ono_slip,
        vstar,
        uc,
        rowc,
        off,
    )
    _viscous_back(u, uc)
    _viscous_back(row, rowc)
    return int(n)


def viscous_assemble(
    cells: Sequence[int],
    T: Floats,
    weight: Floats,
    node_mass: Floats,
    dt: float,
    u: Floats,
    row: Ints,
    off: Ints,
    cols: Ints,
    vals: Floats,
    rhs: Floats,
    node: Ints,
) -> None:
    """The viscous system's blocks, right-hand side and the node of each row (in place)."""
    out = [_viscous_out(a) for a in (cols, vals, rhs, node)]
    _core.viscous_assemble(
        [int(c) for c in cells], T, weight, node_mass, float(dt), u, row, off, *out
    )
    for a, c in zip((cols, vals, rhs, node), out):
        _viscous_back(a, c)


def viscous_worst_row(cols: Ints, vals: Floats, off: Ints, x: Floats, rhs: Floats) -> int:
    """The row of the largest |rhs - A x| of the viscous system (NaN counts as largest)."""
    return int(_core.viscous_worst_row(cols, vals, off, x, rhs))


def viscous_solve(
    cols: Ints,
    vals: Floats,
    node: Ints,
    off: Ints,
    cells: Sequence[int],
    rhs: Floats,
    x: Floats,
    tol: float,
    maxiter: int,
    sweeps: int,
) -> tuple[int, float]:
    """Block-preconditioned CG of the viscous system from the guess in ``x`` (in place).
    Returns (iterations, relative residual)."""
    xc = _viscous_out(x)
    iterations, residual = _core.viscous_solve(
        cols,
        vals,
        node,
        off,
        [int(c) for c in cells],
        rhs,
        xc,
        float(tol),
        int(maxiter),
        int(sweeps),
    )
    _viscous_back(x, xc)
    return int(iterations), float(residual)
