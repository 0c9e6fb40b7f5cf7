"""Build the grid and the particles of a validated case."""

import numpy as np

from .grid import Grid
from .particles import Particles, seed_box, subset


def build_grid(case):
    return Grid.covering(case.domain.size, case.grid.spacing)


def build_particles(case, grid):
    parts = []
    rho = case.material.density
    down = np.asarray(case.physics.gravity, dtype=float)
    for body in case.bodies:
        spacing = grid.spacing / body.particles_per_cell
        amplitude = body.surface_amplitude
        if amplitude == 0.0:
            part = seed_box(body.min, body.max, spacing, rho, body.velocity)
        else:
            part = seed_cosine_box(body.min, body.max, amplitude, spacing, rho, body.velocity)
        if body.initial_pressure == "hydrostatic":
            if amplitude == 0.0:
                corners = np.array(np.meshgrid(*zip(body.min, body.max))).reshape(len(down), -1).T
                top = corners[np.argmax(corners @ -down)]
                part.pressure[:] = rho * ((top - part.x) @ -down)
            else:
                depth = cosine_surface(body.min, body.max, amplitude, part.x[:, 0]) - part.x[:, 1]
                part.pressure[:] = rho * np.linalg.norm(down) * depth
        parts.append(part)
    return Particles.concatenate(parts)


def cosine_surface(lo, hi, amplitude, x):
    """Height of the cosine top of a body: hi[1] + A cos(pi (x - lo[0]) / (hi[0] - lo[0])) (m)."""
    return hi[1] + amplitude * np.cos(np.pi * (x - lo[0]) / (hi[0] - lo[0]))


def seed_cosine_box(lo, hi, amplitude, spacing, density, velocity):
    """A box seeded up to hi[1] + |A|, keeping the particles below the cosine surface."""
    top = [hi[0], hi[1] + abs(amplitude)]
    part = seed_box(lo, top, spacing, density, velocity)
    keep = part.x[:, 1] < cosine_surface(lo, hi, amplitude, part.x[:, 0])
    return subset(part, keep)
