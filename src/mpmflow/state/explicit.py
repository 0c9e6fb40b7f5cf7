"""The weakly compressible comparator's kernels (src/core/explicit_scheme), 2D and 3D.

``grid`` is a ``mpmflow.grid.Grid`` and ``particles`` a ``particles.Particles``; the
scheme's settings and its cell and node work arrays travel as two dataclasses
(``ExplicitSettings``, ``ExplicitWork``) rather than as 40 positional arrays. Arrays are
C-contiguous float64 (``contact``: bool), vectors (count, dim), written in place."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import _core, arrays
from ..arrays import Bools, Floats
from ..grid import Grid
from ..particles import Particles


@dataclass(frozen=True)
class ExplicitSettings:
    """The material and the scheme's settings (SI units)."""

    density: float  # kg/m^3
    bulk: float  # Pa
    gravity: Floats  # m/s^2, (dim,)
    flip: float  # the FLIP fraction per millisecond of flow
    no_slip: Bools  # a flag per side: x_min, x_max, y_min, ...
    smoothing: bool  # the pressure smoothed through the nodes
    full: float  # cells fuller than this are full
    sparse: float  # cells emptier than this take no pressure
    mass_cut: float  # nodes lighter than this share of a full node are left out
    q_lin: float  # the bulk viscosity's linear and quadratic coefficients
    q_quad: float
    tension: float  # Pa: the largest tension the material holds
    max_speed: float  # m/s: a particle faster stops the run


@dataclass
class ExplicitWork:
    """The node and cell arrays the explicit step works in, kept from step to step (the
    cell state ``cell_j`` ... ``cell_p`` is what a checkpoint keeps)."""

    node_mass: Floats
    node_mom: Floats
    v_old: Floats
    v_new: Floats
    contact: Bools
    cell_j: Floats
    cell_vol: Floats
    cell_v0: Floats
    cell_xi: Floats
    cell_p: Floats
    cell_q: Floats
    node_w: Floats
    node_p: Floats
    stats: Floats  # what explicit_steps reports (see there)

    @classmethod
    def zeros(cls, grid: Grid) -> ExplicitWork:
        n, d, c = grid.nnodes, grid.dim, grid.ncells
        return cls(
            node_mass=np.zeros(n),
            node_mom=np.zeros((n, d)),
            v_old=np.zeros((n, d)),
            v_new=np.zeros((n, d)),
            contact=np.zeros((n, d), dtype=np.bool_),
            cell_j=np.zeros(c),
            cell_vol=np.zeros(c),
            cell_v0=np.zeros(c),
            cell_xi=np.zeros((c, d)),
            cell_p=np.zeros(c),
            cell_q=np.zeros(c),
            node_w=np.zeros(n),
            node_p=np.zeros(n),
            stats=np.zeros(6),
        )


def explicit_cell_state(
    grid: Grid, particles: Particles, s: ExplicitSettings, w: ExplicitWork
) -> None:
    """Volumetric strain J and pressure once per cell from the particles in it (in place)."""
    P = particles
    _core.cell_state(
        P.x,
        P.mass,
        P.volume,
        s.density,
        s.bulk,
        s.tension,
        grid.spacing,
        list(grid.cells),
        s.full,
        s.sparse,
        w.cell_j,
        w.cell_vol,
        w.cell_v0,
        w.cell_xi,
        w.cell_p,
    )


def explicit_particle_state(
    grid: Grid, particles: Particles, s: ExplicitSettings, w: ExplicitWork
) -> None:
    """Each particle's volume (its cell's J) and pressure (smoothed through the nodes or its
    cell's), in place."""
    P = particles
    _core.particle_state(
        P.x,
        P.mass,
        P.volume,
        P.pressure,
        s.density,
        grid.spacing,
        list(grid.cells),
        bool(s.smoothing),
        w.cell_j,
        w.cell_vol,
        w.cell_p,
        w.node_w,
        w.node_p,
    )


def explicit_max_speed(v: Floats) -> float:
    """The largest particle speed (m/s); NaN if any speed is NaN."""
    return float(_core.max_speed(v))


def explicit_steps(
    grid: Grid,
    span: float,
    nsteps: int,
    safety: float,
    particles: Particles,
    s: ExplicitSettings,
    w: ExplicitWork,
    margin: float,
) -> None:
    """Explicit steps over ``span`` seconds (in place); particles are put back inside the
    domain ``margin`` (m) from its walls; ``w.stats`` gets [steps taken, time advanced (s),
    smallest step (s), particles put back inside, 1 if stopped on ``max_speed`` else 0,
    largest particle speed (m/s) at the end]."""
    P = particles
    _core.explicit_steps(
        span,
        int(nsteps),
        safety,
        P.x,
        P.v,
        P.pressure,
        P.mass,
        P.volume,
        s.density,
        s.bulk,
        np.ascontiguousarray(s.gravity, dtype=float),
        grid.spacing,
        list(grid.cells),
        s.flip,
        arrays.pair_flags(s.no_slip, np.empty(2 * len(grid.cells))),
        bool(s.smoothing),
        s.full,
        s.sparse,
        s.mass_cut,
        s.q_lin,
        s.q_quad,
        s.tension,
        s.max_speed,
        np.ascontiguousarray(grid.size, dtype=float),
        margin,
        w.node_mass,
        w.node_mom,
        w.v_old,
        w.v_new,
        w.contact,
        w.cell_j,
        w.cell_vol,
        w.cell_v0,
        w.cell_xi,
        w.cell_p,
        w.cell_q,
        w.node_w,
        w.node_p,
        w.stats,
    )
