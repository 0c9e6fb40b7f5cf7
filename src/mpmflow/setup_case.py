"""Build the grid and the particles of a validated case."""

import numpy as np

from .grid import Grid
from .particles import Particles, seed_box


def build_grid(case):
    return Grid.covering(case.domain.size, case.grid.spacing)


def build_particles(case, grid):
    parts = []
    rho = case.material.density
    down = np.asarray(case.physics.gravity, dtype=float)
    for body in case.bodies:
        spacing = grid.spacing / body.particles_per_cell
        part = seed_box(body.min, body.max, spacing, rho, body.velocity)
        if body.initial_pressure == "hydrostatic":
            corners = np.array(np.meshgrid(*zip(body.min, body.max))).reshape(len(down), -1).T
            top = corners[np.argmax(corners @ -down)]
            part.pressure[:] = rho * ((top - part.x) @ -down)
        parts.append(part)
    return Particles.concatenate(parts)
