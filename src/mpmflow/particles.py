"""Material points: arrays of position, velocity, pressure, mass and volume; seeding of bodies."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray


@dataclass
class Particles:
    """Structure of arrays; vectors are (count, dim). SI units: m, m/s, Pa, kg, m^3."""

    x: NDArray[np.float64]
    v: NDArray[np.float64]
    pressure: NDArray[np.float64]
    mass: NDArray[np.float64]
    volume: NDArray[np.float64]

    FIELDS = ("x", "v", "pressure", "mass", "volume")  # the arrays, in constructor order

    @property
    def count(self) -> int:
        return int(self.x.shape[0])

    @classmethod
    def concatenate(cls, parts: Sequence[Particles]) -> Particles:
        return cls(*(np.concatenate([getattr(p, f) for p in parts]) for f in cls.FIELDS))


def subset(particles: Particles, keep: NDArray[np.bool_]) -> Particles:
    """The particles selected by the boolean mask ``keep`` (copies)."""
    return Particles(*(getattr(particles, f)[keep] for f in Particles.FIELDS))
