"""Domain walls: which wall nodes hold the material, and their velocity conditions.

A wall is a contact condition. Each step starts with the wall nodes that carry a pressure
unknown in contact, and the others only where the material presses into the wall; the
pressure step then releases the nodes where holding the material would need a negative
pressure while it moves away from the wall (see ``pressure.PressureProjection.project``).
"""

import numpy as np

from .kernels import walls2d


def wall_contact(grid):
    """(nnodes, dim) mask of the wall nodes, all in contact."""
    if grid.dim != 2:
        raise NotImplementedError("only 2D grids are implemented")
    contact = np.zeros((grid.nnodes, grid.dim), dtype=np.bool_)
    walls2d.wall_nodes_2d(grid.cells[0], grid.cells[1], contact)
    return contact


def apply_walls(grid, v, contact, kind):
    """Velocity conditions at wall nodes (in place); ``kind``: slip | no_slip."""
    walls2d.apply_walls_2d(grid.cells[0], grid.cells[1], v, contact, kind == "no_slip")


def outward_normal_velocity(grid, v):
    """(nnodes, dim): v_k times the outward normal sign of the wall normal to axis k (0 off walls)."""
    out = np.zeros_like(v)
    nodes = grid.nodes
    idx = np.arange(grid.nnodes)
    stride = 1
    for k in range(grid.dim):
        pos = (idx // stride) % nodes[k]
        out[pos == 0, k] = -v[pos == 0, k]
        out[pos == nodes[k] - 1, k] = v[pos == nodes[k] - 1, k]
        stride *= nodes[k]
    return out
