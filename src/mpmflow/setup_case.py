"""Build the grid and the particles of a validated case."""

from .grid import Grid
from .particles import Particles, seed_box


def build_grid(case):
    return Grid.covering(case.domain.size, case.grid.spacing)


def build_particles(case, grid):
    parts = []
    for body in case.bodies:
        spacing = grid.spacing / body.particles_per_cell
        parts.append(seed_box(body.min, body.max, spacing, case.material.density, body.velocity))
    return Particles.concatenate(parts)
