"""Domain walls: which wall nodes hold the material, and their velocity conditions.

A wall is a contact condition. Each step starts with the wall nodes that carry a pressure
unknown in contact, and the others only where the material presses into the wall; the
pressure step then releases the nodes where holding the material would need a negative
pressure while it moves away from the wall (see ``pressure.PressureProjection.project``).
"""

import numpy as np

from .kernels import walls2d


def outward_normals(grid):
    """(nnodes, dim): the outward normal sign (-1 or +1) of the wall normal to axis k at each
    wall node, 0 where the node is not on such a wall. Fixed for a grid: compute it once."""
    if grid.dim != 2:
        raise NotImplementedError("only 2D grids are implemented")
    out = np.zeros((grid.nnodes, grid.dim), dtype=np.int8)
    idx = np.arange(grid.nnodes)
    stride = 1
    for k, n in enumerate(grid.nodes):
        pos = (idx // stride) % n
        out[pos == 0, k] = -1
        out[pos == n - 1, k] = 1
        stride *= n
    return out


def wall_contact(grid):
    """(nnodes, dim) mask of the wall nodes, all in contact."""
    return outward_normals(grid) != 0


def apply_walls(grid, v, contact, kind):
    """Velocity conditions at wall nodes (in place); ``kind``: slip | no_slip."""
    walls2d.apply_walls_2d(grid.cells[0], grid.cells[1], v, contact, kind == "no_slip")
