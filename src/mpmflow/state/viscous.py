"""The viscous materials' kernels: effective viscosity, the implicit viscous system and
its solve (src/core/rheology.hpp, viscous)."""

import numpy as np

from .. import _core
from . import arrays

# the rheology's model codes (``mpmflow.materials``) and the implicit viscous predictor
# (src/core/rheology.hpp, src/core/viscous.hpp)
WATER, NEWTONIAN, HERSCHEL_BULKLEY, MU_I = (
    _core.WATER,
    _core.NEWTONIAN,
    _core.HERSCHEL_BULKLEY,
    _core.MU_I,
)


def viscosity(model, par, rate, p):
    """The effective viscosity (Pa s) of rheology ``model`` with parameters ``par`` at strain
    rate ``rate`` (1/s) and pressure ``p`` (Pa)."""
    return _core.viscosity(
        int(model), np.ascontiguousarray(par, dtype=float), float(rate), float(p)
    )


def _viscous_out(a):
    """``a`` itself when C-contiguous (the core writes into it), else a C-contiguous copy to
    be copied back with ``_viscous_back``."""
    return a if a.flags.c_contiguous else np.ascontiguousarray(a)


def _viscous_back(a, c):
    if c is not a:
        a[...] = c


def gauss_gradients(cells, h):
    """T[a, b, m, k] = int over a full cell of dN_a/dx_m dN_b/dx_k (2^D x 2^D x D x D)."""
    D = len(cells)
    T = np.empty((1 << D, 1 << D, D, D))
    _core.gauss_gradients([int(c) for c in cells], float(h), T)
    return T


def cell_viscosity(cells, h, theta, open_, enclosed, full, v, p_node, model, par, eta, weight):
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
    node_mass,
    wall_node,
    wall_axis,
    wall_no_slip,
    contact,
    onode,
    ocontact,
    ono_slip,
    vstar,
    u,
    row,
    off,
):
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
    return n


def viscous_assemble(cells, T, weight, node_mass, dt, u, row, off, cols, vals, rhs, node):
    """The viscous system's blocks, right-hand side and the node of each row (in place)."""
    out = [_viscous_out(a) for a in (cols, vals, rhs, node)]
    _core.viscous_assemble(
        [int(c) for c in cells], T, weight, node_mass, float(dt), u, row, off, *out
    )
    for a, c in zip((cols, vals, rhs, node), out):
        _viscous_back(a, c)


def viscous_worst_row(cols, vals, off, x, rhs):
    """The row of the largest |rhs - A x| of the viscous system (NaN counts as largest)."""
    return _core.viscous_worst_row(cols, vals, off, x, rhs)


def viscous_solve(cols, vals, node, off, cells, rhs, x, tol, maxiter, sweeps):
    """Block-preconditioned CG of the viscous system from the guess in ``x`` (in place).
    Returns (iterations, relative residual)."""
    xc = _viscous_out(x)
    result = _core.viscous_solve(
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
    return result
