"""The global particle lattice: the points (k + 1/2) s, k integer, of spacing s =
grid.spacing / particles_per_cell along each axis. Every body takes its particles from it,
so particles of neighbouring bodies never overlap and a box that starts on a grid line gets
particles aligned with the cells."""

import math
from collections.abc import Iterator, Sequence

import numpy as np

# a box's corner (m): a list or an array of its coordinates
Corner = Sequence[float] | np.ndarray

CHUNK = 2**20  # lattice points per chunk of a containment pass


def lattice_indices(a: float, b: float, spacing: float) -> tuple[int, int]:
    """(k0, k1): the lattice points (k + 1/2) * spacing with k0 <= k <= k1 lie in [a, b)."""
    k0 = math.ceil(a / spacing - 0.5 - 1e-9)
    k1 = math.floor(b / spacing - 0.5 - 1e-9)
    return k0, k1


def lattice_axes(lo: Corner, hi: Corner, spacing: float) -> list[np.ndarray]:
    """The lattice's coordinates in [lo, hi) along each axis (m)."""
    axes = []
    for a, b in zip(lo, hi):
        k0, k1 = lattice_indices(a, b, spacing)
        axes.append((np.arange(k0, k1 + 1) + 0.5) * spacing)
    return axes


def lattice_count(lo: Corner, hi: Corner, spacing: float) -> int:
    """Number of lattice points in [lo, hi) (exact integer)."""
    n = 1
    for a, b in zip(lo, hi):
        k0, k1 = lattice_indices(a, b, spacing)
        n *= max(0, k1 - k0 + 1)
    return n


def lattice_chunks(
    lo: Corner, hi: Corner, spacing: float, chunk: int = CHUNK
) -> Iterator[np.ndarray]:
    """The lattice points in [lo, hi) as (n, D) arrays of about ``chunk`` points, slabs along
    the last axis (so that a pass over many points holds few at once)."""
    axes = lattice_axes(lo, hi, spacing)
    if any(len(a) == 0 for a in axes):
        return
    per_slab = math.prod(len(a) for a in axes[:-1])
    step = max(1, chunk // per_slab)
    for j in range(0, len(axes[-1]), step):
        mesh = np.meshgrid(*axes[:-1], axes[-1][j : j + step], indexing="ij")
        yield np.stack([m.ravel(order="F") for m in mesh], axis=1)


def lattice_in_box(lo: Corner, hi: Corner, spacing: float) -> np.ndarray:
    """Points of the lattice ``(k + 1/2) * spacing`` (k integer) that lie inside [lo, hi).

    The lattice is global, so particles of neighbouring boxes never overlap and a box that
    starts on a grid line gets exactly ``spacing``-spaced particles aligned with the cells.
    """
    axes = lattice_axes(lo, hi, spacing)
    mesh = np.meshgrid(*axes, indexing="ij")
    return np.stack([m.ravel(order="F") for m in mesh], axis=1)
