"""Material points: arrays of position, velocity, pressure, mass and volume; seeding of bodies."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from typing_extensions import Self


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


def keep(particles: Particles, mask: NDArray[np.bool_]) -> None:
    """Keep only the particles ``mask`` selects, in place: each array of ``particles`` is
    replaced by its kept rows, so every holder of the object sees the new ones."""
    for name in Particles.FIELDS:
        setattr(particles, name, getattr(particles, name)[mask])


@dataclass
class Tally:
    """Particles counted as they cross a boundary: how many, their mass (kg) and volume
    (m^3); as a checkpoint keeps them, three numbers."""

    count: int = 0
    mass: float = 0.0
    volume: float = 0.0

    def add(self, count: int, mass: float, volume: float) -> None:
        self.count += count
        self.mass += mass
        self.volume += volume

    def as_array(self) -> NDArray[np.float64]:
        return np.array([self.count, self.mass, self.volume], dtype=np.float64)

    @classmethod
    def of_array(cls, a: NDArray[np.float64]) -> Self:
        """The tally a checkpoint kept (``as_array``)."""
        out = cls()
        out.count, out.mass, out.volume = int(a[0]), float(a[1]), float(a[2])
        return out
