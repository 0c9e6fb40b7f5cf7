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
from ..particles import Particles, Tally, keep

if TYPE_CHECKING:
    from ..case import Case


def sides(case: Case) -> Bools:
    """Outlet flags of the domain's sides in the order x_min, x_max, y_min, ... (bool)."""
    return np.array(case.domain.outlet_sides(), dtype=np.bool_)


@dataclass
class Outflow(Tally):
    """What has left through the outlets: particles, mass (kg) and volume (m^3)."""

    def drain(self, P: Particles, mass: Floats, volume: Floats) -> Bools | None:
        """Remove from ``P`` the particles the core retired (mass 0), in place (its arrays
        replaced by the kept ones), and add them to the totals; ``mass`` and ``volume`` are
        the particles' own (the core zeroed the retired ones'). Returns the mask of the
        particles kept, or None when none left."""
        gone: Bools = P.mass == 0.0
        if not gone.any():
            return None
        self.add(int(gone.sum()), float(mass[gone].sum()), float(volume[gone].sum()))
        kept: Bools = ~gone
        keep(P, kept)
        return kept
