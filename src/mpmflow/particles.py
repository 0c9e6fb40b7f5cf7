"""Material points: arrays of position, velocity, pressure, mass and volume; seeding of bodies."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np


@dataclass
class Particles:
    """Structure of arrays; vectors are (count, dim). SI units: m, m/s, Pa, kg, m^3."""

    x: np.ndarray
    v: np.ndarray
    pressure: np.ndarray
    mass: np.ndarray
    volume: np.ndarray

    FIELDS = ("x", "v", "pressure", "mass", "volume")  # the arrays, in constructor order

    @property
    def count(self) -> int:
        return self.x.shape[0]

    @classmethod
    def concatenate(cls, parts: Sequence[Particles]) -> Particles:
        return cls(*(np.concatenate([getattr(p, f) for p in parts]) for f in cls.FIELDS))


def subset(particles: Particles, keep: np.ndarray) -> Particles:
    """The particles selected by the boolean mask ``keep`` (copies)."""
    return Particles(*(getattr(particles, f)[keep] for f in Particles.FIELDS))
