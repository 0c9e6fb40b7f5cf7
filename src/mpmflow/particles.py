"""Material points: arrays of position, velocity, pressure, mass and volume; seeding of bodies."""

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
    def count(self):
        return self.x.shape[0]

    @classmethod
    def concatenate(cls, parts):
        return cls(*(np.concatenate([getattr(p, f) for p in parts]) for f in cls.FIELDS))


def subset(particles, keep):
    """The particles selected by the boolean mask ``keep`` (copies)."""
    return Particles(*(getattr(particles, f)[keep] for f in Particles.FIELDS))


def lattice_in_box(lo, hi, spacing):
    """Points of the lattice ``(k + 1/2) * spacing`` (k integer) that lie inside [lo, hi).

    The lattice is global, so particles of neighbouring boxes never overlap and a box that
    starts on a grid line gets exactly ``spacing``-spaced particles aligned with the cells.
    """
    from .bodies import lattice_indices

    axes = []
    for a, b in zip(lo, hi):
        k0, k1 = lattice_indices(a, b, spacing)
        axes.append((np.arange(k0, k1 + 1) + 0.5) * spacing)
    mesh = np.meshgrid(*axes, indexing="ij")
    return np.stack([m.ravel(order="F") for m in mesh], axis=1)


def seed_box(lo, hi, spacing, density, velocity):
    """Particles filling a box; each carries the volume spacing**dim and mass density*volume."""
    x = lattice_in_box(lo, hi, spacing)
    n, dim = x.shape
    vol = np.full(n, spacing**dim)
    return Particles(
        x=x,
        v=np.tile(np.asarray(velocity, dtype=float), (n, 1)),
        pressure=np.zeros(n),
        mass=vol * density,
        volume=vol,
    )
