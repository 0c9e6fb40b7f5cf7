"""The domain's walls: every wall node of the grid with the wall it lies on (its axis and
outward sign: the wall's normal) and the wall's condition (slip or no-slip) from the case's
``domain.walls``. A periodic axis has no walls. The core applies them as contact conditions
(src/core/walls.hpp): a wall node holds the material where it presses into the wall and
lets it go where holding it would need suction. An outlet side is no wall (outlets.py)."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from .. import state
from ..arrays import Bools, Floats, Ints
from ..grid import Grid

if TYPE_CHECKING:  # the case asks this package for its boundaries
    from ..case import Case


@dataclass(frozen=True)
class Walls:
    """One entry per (wall node, wall) pair: the walls normal to axis 0 first, then axis 1,
    ...; the lower wall (sign -1) before the upper. A node on an edge or corner has a pair
    per wall it lies on."""

    node: Ints  # (n,) int64: the node's index
    axis: Ints  # (n,) int64: the axis the wall is normal to
    sign: Floats  # (n,) float: -1 at the lower wall (at 0), +1 at the upper
    no_slip: Bools  # (n,) bool: the wall's condition is no-slip (or bonded)
    bonded: Bools  # (n,) bool: the wall is bonded (held in tension too)

    def as_tuple(self) -> tuple[Ints, Ints, Floats, Bools]:
        """(node, axis, sign, no_slip), as the core's state takes them."""
        return self.node, self.axis, self.sign, self.no_slip


def side_conditions(case: Case) -> Bools:
    """No-slip flags of the domain's sides in the order x_min, x_max, y_min, ... (bool)."""
    return np.array(case.domain.no_slip_sides(), dtype=np.bool_)


def of_case(case: Case, grid: Grid, openings: Mapping[int, Ints] | None = None) -> Walls:
    """The walls of the case's domain on its grid (an outlet side has none: its nodes are
    never held; ``boundaries.outlets``). ``openings``: the inlets' (``inlets.Tables``), side
    -> its nodes in the opening: those pairs are bonded no-slip, held to the inflow."""
    node, axis, sign = state.wall_pairs(tuple(int(c) for c in grid.cells), grid.periodic)
    side = 2 * axis + (sign > 0)
    wall = ~np.array(case.domain.outlet_sides(), dtype=np.bool_)[side]
    no_slip = side_conditions(case)[side]
    bonded = np.array(case.domain.bonded_sides(), dtype=np.bool_)[side]
    for s, nodes in (openings or {}).items():
        opening = (side == s) & np.isin(node, nodes)
        no_slip = no_slip | opening
        bonded = bonded | opening
    return Walls(node[wall], axis[wall], sign[wall], no_slip[wall], bonded[wall])
