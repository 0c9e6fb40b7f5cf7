"""Particle-to-grid and grid-to-particle transfers (docs/method.md, steps 1 and 7)."""

import numpy as np

from .kernels import transfer2d


def particles_to_grid(grid, particles, node_mass, node_mom, node_vel, node_vol):
    """Lumped nodal mass, momentum, velocity v_i^t and material volume (in place)."""
    if grid.dim != 2:
        raise NotImplementedError("only 2D grids are implemented")
    nx, ny = grid.cells
    transfer2d.particles_to_grid_2d(particles.x, particles.v, particles.mass, particles.volume,
                                    grid.spacing, nx, ny, node_mass, node_mom, node_vol)
    transfer2d.nodal_velocity(node_mass, node_mom, node_vel)


def grid_to_particles(grid, particles, v_old, v_new, p_node, dt, flip):
    """FLIP/PIC velocity, position and pressure update of the particles (eqs. 19-21)."""
    nx, ny = grid.cells
    transfer2d.grid_to_particles_2d(particles.x, particles.v, particles.pressure, grid.spacing,
                                    nx, ny, v_old, v_new, p_node, dt, flip)


def keep_inside(grid, particles, margin_fraction=1e-6):
    """Put particles that crossed a wall back inside the domain; returns how many."""
    upper = np.asarray(grid.size, dtype=float)
    return int(transfer2d.keep_inside(particles.x, particles.v, upper,
                                      margin_fraction * grid.spacing))
