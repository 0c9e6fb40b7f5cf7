"""The fixed background grid: uniform square (cubic) cells covering the domain [0, size]."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

if TYPE_CHECKING:  # the case makes its grid (case.model imports this module)
    from .case import Case


@dataclass(frozen=True)
class Grid:
    """Uniform grid of ``cells[k]`` cells of side ``spacing`` (m) along each axis k."""

    spacing: float
    cells: tuple[int, ...]
    #: periodic[k]: axis k wraps round (its last plane of nodes is an image of its first);
    #: empty: no periodic axis
    periodic: tuple[bool, ...] = ()

    @classmethod
    def of_case(cls, case: Case) -> Grid:
        """The grid of a validated case: its domain, spacing and periodic axes."""
        return cls.covering(case.domain.size, case.grid.spacing, periodic=case.domain.periodic)

    @classmethod
    def covering(
        cls,
        size: Sequence[float],
        spacing: float,
        rtol: float = 1e-6,
        periodic: Sequence[bool] | None = None,
    ) -> Grid:
        """The grid of the given spacing that covers the box [0, size], periodic along the
        axes where ``periodic[k]`` (None: none).

        Walls lie on grid lines, so a side that is not a whole number of cells is extended
        to the next whole cell (by less than one spacing); ``adjusted`` tells the caller.
        """
        counts = []
        for length in size:
            n = length / spacing
            counts.append(
                max(1, int(round(n)) if abs(n - round(n)) <= rtol * n else int(np.ceil(n)))
            )
        flags = tuple(bool(p) for p in periodic) if periodic and any(periodic) else ()
        return cls(float(spacing), tuple(counts), flags)

    def adjusted(self, size: Sequence[float], rtol: float = 1e-6) -> bool:
        """True when the grid's extent differs from the requested domain size."""
        return any(abs(a - b) > rtol * b for a, b in zip(self.size, size))

    @property
    def dim(self) -> int:
        return len(self.cells)

    @property
    def nodes(self) -> tuple[int, ...]:
        return tuple(n + 1 for n in self.cells)

    @property
    def ncells(self) -> int:
        return math.prod(self.cells)

    @property
    def nnodes(self) -> int:
        return math.prod(self.nodes)

    @property
    def size(self) -> NDArray[np.float64]:
        return np.array(self.cells, dtype=float) * self.spacing

    @property
    def cell_volume(self) -> float:
        return self.spacing**self.dim

    def cell_centres(self, axis: int) -> NDArray[np.float64]:
        """Coordinates (m) of the cell centres along one axis."""
        return (np.arange(self.cells[axis], dtype=np.float64) + 0.5) * self.spacing

    def node_coordinates(self) -> NDArray[np.float64]:
        """(nnodes, dim) coordinates of the nodes in flat order (x fastest)."""
        axes = [np.arange(n) * self.spacing for n in self.nodes]
        mesh = np.meshgrid(*axes, indexing="ij")
        return np.stack([m.ravel(order="F") for m in mesh], axis=1)

    def interpolate(
        self, values: NDArray[np.float64], x: NDArray[np.float64]
    ) -> NDArray[np.float64]:
        """A nodal field (nnodes, flat order) at the points ``x`` (n, dim; m), interpolated
        multilinearly from the nodes of the cell holding each (points past the last cell
        take its nodes)."""
        nodes = np.array([int(n) for n in self.nodes])
        s = x / self.spacing
        i0 = np.clip(np.floor(s).astype(np.int64), 0, nodes - 2)
        w = s - i0
        strides = np.cumprod(np.concatenate([[1], nodes[:-1]]))
        value = np.zeros(x.shape[0])
        for corner in np.ndindex(*(2,) * self.dim):
            c = np.array(corner)
            value += np.prod(np.where(c, w, 1 - w), axis=1) * values[(i0 + c) @ strides]
        return value
