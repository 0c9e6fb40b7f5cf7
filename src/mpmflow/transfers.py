"""Particle-to-grid and grid-to-particle transfers (docs/method.md, steps 1, 2 and 7)."""

import numpy as np

from .kernels import transfer2d

NO_FACES = np.zeros(0)  # an empty array: no volume correction
FLIP_TIME = 1e-3  # s: solver.flip is the FLIP fraction per this much simulated time


def flip_per_step(flip, dt):
    """The FLIP fraction of one step of dt: flip^(dt / 1 ms), the same PIC damping per second
    whatever the step (both schemes)."""
    return flip ** (dt / FLIP_TIME)


def particles_to_grid(grid, particles, bins, gravity, dt, node_mass, node_mom, node_vol, v_old,
                      v_star, cell_vol=None):
    """Lumped nodal mass, momentum, material volume, velocity v_i^t and the predictor
    v*_i = v_i^t + dt g (in place); ``bins``: the particles sorted by cell. ``cell_vol``
    (optional): the particles' volume on the cell centres, for the volume correction."""
    if grid.dim != 2:
        raise NotImplementedError("only 2D grids are implemented")
    nx, ny = grid.cells
    transfer2d.particles_to_grid_2d(particles.x, particles.v, particles.mass, particles.volume,
                                    bins.order, bins.start, grid.spacing, nx, ny, gravity, dt,
                                    node_mass, node_mom, node_vol, v_old, v_star,
                                    NO_FACES if cell_vol is None else cell_vol)


def grid_to_particles(grid, particles, v_old, v_new, p_node, dt, flip, faces=None,
                      margin_fraction=1e-6):
    """FLIP/PIC velocity, position and pressure update of the particles (eqs. 19-21), with
    the volume correction's displacement ``faces`` (``VolumeCorrection.faces``) added to the
    positions; the particles that crossed a wall are put back inside the domain. Returns how
    many were."""
    nx, ny = grid.cells
    upper = np.asarray(grid.size, dtype=float)
    dx_face, dy_face = faces if faces is not None else (NO_FACES, NO_FACES)
    return int(transfer2d.grid_to_particles_2d(
        particles.x, particles.v, particles.pressure, grid.spacing, nx, ny, v_old, v_new,
        p_node, dt, flip, upper, margin_fraction * grid.spacing, dx_face, dy_face))
