"""Rotations of rigid bodies: the matrix of a unit quaternion, as the core writes a body's
orientation (src/core/bodies.cpp, bodies.csv's q columns and the state's)."""

import numpy as np
from numpy.typing import NDArray


def quaternion_matrix(w: float, x: float, y: float, z: float) -> NDArray[np.float64]:
    """The rotation matrix (3 x 3) of the quaternion (w, x, y, z), normalised first."""
    norm = float(np.sqrt(w * w + x * x + y * y + z * z))
    w, x, y, z = w / norm, x / norm, y / norm, z / norm
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )
