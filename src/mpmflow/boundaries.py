"""Domain walls: which wall nodes hold the material, and their velocity conditions.

A wall is a contact condition. Each step starts with the wall nodes that carry a pressure
unknown in contact, and the others only where the material presses into the wall; the
pressure step then releases the nodes where holding the material would need a negative
pressure while it moves away from the wall (see ``pressure.PressureProjection.project``).
"""

from .kernels import walls2d


def apply_walls(grid, v, contact, kind):
    """Velocity conditions at wall nodes (in place); ``kind``: slip | no_slip."""
    walls2d.apply_walls_2d(grid.cells[0], grid.cells[1], v, contact, kind == "no_slip")
