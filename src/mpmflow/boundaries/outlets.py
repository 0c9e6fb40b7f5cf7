"""Outlets: the open sides of the domain (``domain.walls = "outlet"``). An outlet has no wall
pairs (``walls.of_case`` leaves them out), so its nodes are never held: the velocity there
is free and the pressure takes the natural condition of the projection's weak form. The core
retires a particle that crosses an outlet (src/core/transfer.hpp, ``Outlets``: its mass and
volume set to 0, so that it carries nothing to the grid); between chunks ``Outflow.drain``
removes the retired particles from the particle arrays and sums what left."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ..arrays import Bools, Floats
from ..particles import Particles

if TYPE_CHECKING:
    from ..case import Case


def sides(case: Case) -> Bools:
    """Outlet flags of the domain's sides in the order x_min, x_max, y_min, ... (bool)."""
    return np.array(case.domain.outlet_sides(), dtype=np.bool_)


@dataclass
class Outflow:
    """What has left through the outlets: particles, mass (kg) and volume (m^3)."""

    count: int = 0
    mass: float = 0.0
    volume: float = 0.0

    def drain(self, P: Particles, mass: Floats, volume: Floats) -> Bools | None:
        """Remove from ``P`` the particles the core retired (mass 0), in place (its arrays
        replaced by the kept ones), and add them to the totals; ``mass`` and ``volume`` are
        the particles' own (the core zeroed the retired ones'). Returns the mask of the
        particles kept, or None when none left."""
        gone: Bools = P.mass == 0.0
        if not gone.any():
            return None
        self.count += int(gone.sum())
        self.mass += float(mass[gone].sum())
        self.volume += float(volume[gone].sum())
        keep = ~gone
        for name in Particles.FIELDS:
            setattr(P, name, getattr(P, name)[keep])
        return keep

    def as_array(self) -> Floats:
        """The totals as a checkpoint keeps them."""
        return np.array([self.count, self.mass, self.volume], dtype=np.float64)

    @classmethod
    def of_array(cls, a: Floats) -> Outflow:
        return cls(int(a[0]), float(a[1]), float(a[2]))
