"""Domain walls: the velocity conditions at wall nodes (``apply_walls``).

A wall is a contact condition. Which wall nodes hold the material is decided in the
pressure step, not here: ``pressure.PressureProjection.project`` calls
``kernels.walls2d.start_contact_2d`` (each step starts with the wall nodes that carry a
pressure unknown in contact, and the others only where the material presses into the wall)
and ``kernels.walls2d.release_contact_2d`` (it releases the nodes where holding the material
would need a negative pressure while it moves away from the wall).
"""

from .kernels import walls2d


def apply_walls(grid, v, contact, kind):
    """Velocity conditions at wall nodes (in place); ``kind``: slip | no_slip."""
    walls2d.apply_walls_2d(grid.cells[0], grid.cells[1], v, contact, kind == "no_slip")
