"""Velocity inlets (``[[inlets]]``): water entering the domain through part of a side at a
given speed, uniform or profiled over the height. The core does the work each step
(src/core/inlets.hpp): the inlet's wall nodes are held to the inflow (``Tables.held``, bonded
no-slip wall pairs, ``walls.of_case``), and each row of the particles' lattice across the
opening emits a particle each time the inflow there has travelled one particle spacing.
This module builds those tables, and between chunks appends the pool of dormant particles
a chunk may emit (``Inflow.supply``) and trims what it did not (``Inflow.settle``),
counting what entered.

The opening is the side's nodes from the floor up to the inlet's level, rounded to the
particles' lattice (a whole number of rows of spacing s): every node whose dual segment
[z - h/2, z + h/2] along the last axis reaches below that level is held to the inflow
there (``_node_speed``), the node at the surface at the full speed, as the water round it
moves. (Holding it to the share of its segment below the level, which makes the grid's
flux the particles' exactly, dragged the top rows of the stream: a stream entering at
1 m/s without gravity slowed to 0.98-0.99 m/s within 0.3 m of the inlet.)"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from ..arrays import Bools, Floats, Ints
from ..geometry.lattice import lattice_axes
from ..grid import Grid
from ..particles import Particles, Tally, keep

if TYPE_CHECKING:
    from ..case import Case
    from ..case.inlets import Inlet


@dataclass(frozen=True)
class Tables:
    """The inlets' tables on a grid (empty arrays where there are none)."""

    held: Floats  # (nnodes, D) m/s: the velocity of the inlet nodes; (0, D): no inlet
    # side (2 axis + upper) -> the side's nodes in the opening
    openings: dict[int, Ints]
    axis: Ints  # (n,) the axis normal to each inlet's side
    direction: Floats  # (n,) +1: the side at 0 (flow towards +axis), -1: at domain.size
    first: Ints  # (n + 1,) inlet q's layer rows are first[q]:first[q + 1]
    layer: Floats  # (rows, D) m: a layer's positions, on the side along the axis
    speed: Floats  # (rows,) m/s: the inflow's speed at each row (a profile)
    spacing: Floats  # (n,) m
    mass: Floats  # (n,) kg: each emitted particle's
    volume: Floats  # (n,) m^3 (m^2 in 2D)

    @property
    def present(self) -> bool:
        return bool(self.direction.shape[0] > 0)

    @property
    def particle(self) -> tuple[float, float]:
        """(mass, volume) of every particle the inlets emit (one lattice for all inlets)."""
        return float(self.mass[0]), float(self.volume[0])

    def core(self) -> tuple[Floats | Ints, ...]:
        """The arrays ``state.step_state`` takes as its ``inlets``."""
        return (
            self.axis,
            self.direction,
            self.speed,
            self.first,
            self.layer,
            self.spacing,
            self.mass,
            self.volume,
        )

    def row_spacing(self) -> Floats:
        """Each row's particle spacing (m), its inlet's."""
        spacing: Floats = np.repeat(self.spacing, np.diff(self.first))
        return spacing

    def pool_size(self, travel: Floats, duration: float) -> int:
        """The particles the inlets may emit within ``duration`` (s) from where each row's
        next particle is (``travel``, m): the whole spacings speed x duration covers, and one
        more against rounding, row by row."""
        emitted = np.floor((travel + self.speed * duration) / self.row_spacing()) + 1
        return int(np.sum(emitted.astype(np.int64)))


def of_case(case: Case, grid: Grid) -> Tables:
    """The case's inlets on its grid."""
    D = grid.dim
    up = D - 1
    nodes = grid.node_coordinates()
    held = np.zeros((grid.nnodes, D)) if case.inlets else np.zeros((0, D))
    openings: dict[int, Ints] = {}
    size = grid.size
    apic = case.solver.transfer == "apic"
    axis, direction, speeds, first, layers, spacing, mass, volume = [], [], [], [0], [], [], [], []
    for inlet in case.inlets:
        k = inlet.axis
        s = inlet.spacing(grid.spacing)
        level = inlet.top(grid.spacing)
        # the side's nodes, and those whose dual segment along the last axis reaches into
        # the opening
        on_side = np.isclose(nodes[:, k], 0.0 if inlet.lower else size[k], atol=1e-9 * grid.spacing)
        inside = np.flatnonzero(on_side & (nodes[:, up] - grid.spacing / 2 < level - 1e-9 * s))
        sign = 1.0 if inlet.lower else -1.0
        held[inside, k] = sign * _node_speed(inlet, nodes[inside, up], level, grid.spacing, apic)
        openings[2 * k + (0 if inlet.lower else 1)] = inside
        # one layer: the lattice across the side, rows below the level; on the side along k
        lo_box = np.zeros(D)
        hi_box = size.astype(float).copy()
        hi_box[up] = level
        cross = lattice_axes(lo_box, hi_box, s)
        cross[k] = np.array([0.0 if inlet.lower else size[k]])
        mesh = np.meshgrid(*cross, indexing="ij")
        layer = np.stack([m.ravel(order="F") for m in mesh], axis=1)
        axis.append(k)
        direction.append(sign)
        speeds.append(inlet.speed_at(layer[:, up]))
        layers.append(layer)
        first.append(first[-1] + layer.shape[0])
        spacing.append(s)
        volume.append(s**D)
        mass.append(case.material.density * s**D)
    return Tables(
        held=held,
        openings=openings,
        axis=np.array(axis, dtype=np.int64),
        direction=np.array(direction, dtype=float),
        first=np.array(first, dtype=np.int64),
        layer=np.concatenate(layers) if layers else np.zeros((0, D)),
        speed=np.concatenate(speeds) if speeds else np.zeros(0),
        spacing=np.array(spacing, dtype=float),
        mass=np.array(mass, dtype=float),
        volume=np.array(volume, dtype=float),
    )


def _node_speed(inlet: Inlet, z: Floats, level: float, h: float, apic: bool) -> Floats:
    """The speed (m/s) an opening's nodes at heights z hold: the velocity the step's own
    particle-to-grid transfer gives a node from a lattice that carries the profile. APIC
    carries each particle's velocity gradient to the node, so a node holds the profile's
    value at its height (below the level). FLIP and PIC average the particles round a node,
    so a node holds the profile averaged over the water in its support, [z - h, z + h]
    within [0, level], weighted by its hat function. (Holding a FLIP node at the profile's
    value at its height, 0.5 m/s at the floor of a profile rising by 10 m/s a metre, slowed
    the particles of the lowest row by 5%: the floor node's particles lie above it, at
    0.54 m/s on average; holding an APIC node at the average slowed its top row by 3%.) A
    uniform inflow holds every node at its speed either way."""
    if apic or inlet.profile is None:
        point: Floats = inlet.speed_at(np.minimum(z, level))
        return point
    t = (np.arange(QUADRATURE) + 0.5) / QUADRATURE * 2.0 - 1.0  # midpoints in [-1, 1]
    heights = z[:, None] + t[None, :] * h
    weight = (1.0 - np.abs(t))[None, :] * ((heights >= 0.0) & (heights <= level))
    speed: Floats = np.sum(weight * inlet.speed_at(heights), axis=1) / np.sum(weight, axis=1)
    return speed


QUADRATURE = 64  # midpoints across a node's support (the profile is piecewise linear)


def _zero_rows(a: Floats, size: int) -> Floats:
    """``a`` with ``size`` rows of zeros after its own."""
    return np.concatenate([a, np.zeros((size, *a.shape[1:]))])


@dataclass
class Inflow(Tally):
    """What has entered through the inlets: particles, mass (kg) and volume (m^3), and the
    pool of the chunk in progress (``pool``: its first particle and end)."""

    pool: tuple[int, int] = field(default=(0, 0))

    def supply(self, P: Particles, size: int, extra: list[Floats]) -> tuple[int, int]:
        """Append ``size`` dormant particles (mass, volume 0) to ``P`` in place and zero rows
        to each array of ``extra`` (returned in that list, the same order); returns the
        pool's range (first, end) for the core."""
        n = P.count
        for name in Particles.FIELDS:
            setattr(P, name, _zero_rows(getattr(P, name), size))
        for j, a in enumerate(extra):
            extra[j] = _zero_rows(a, size)
        self.pool = (n, n + size)
        return self.pool

    def settle(self, P: Particles, emitted_end: int, particle: tuple[float, float]) -> Bools | None:
        """After a chunk: count the pool's particles the inlets emitted (up to
        ``emitted_end``, the core's ``inlet_next``; each of ``particle`` = (mass, volume), the
        same for every inlet) and remove the rest from ``P`` in place; returns the mask of
        the particles kept (None: nothing removed)."""
        first, end = self.pool
        self.pool = (0, 0)
        emitted = emitted_end - first
        self.add(emitted, emitted * particle[0], emitted * particle[1])
        if emitted_end == end:
            return None
        kept = np.ones(P.count, dtype=np.bool_)
        kept[emitted_end:end] = False
        keep(P, kept)
        return kept
