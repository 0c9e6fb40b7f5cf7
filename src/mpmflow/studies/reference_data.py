"""Reference data beside the project (``../shared/data``) and the error measures against it.

The folder is found from the environment variable MPMFLOW_DATA, else as ``shared/data``
beside the repository. Lengths are normalised by the column width a (m).
"""

import os
from collections.abc import Sequence
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

G = 9.81
VOF_AR2 = "reference/vof_interfoam_ar2_dx0.004_slip.csv"
MM_HEIGHT_AR2 = "validation/martin_moyce_1952_n2eq2_a2.25in_height_table6.csv"

Series = NDArray[np.float64] | Sequence[float]  # a simulated series (s, m)


def data_dir() -> Path:
    env = os.environ.get("MPMFLOW_DATA")
    path = Path(env) if env else Path(__file__).resolve().parents[4] / "shared" / "data"
    if not path.is_dir():
        raise FileNotFoundError(
            f"Reference data not found at {path}. Put the project's shared/ folder beside the "
            "repository, or set MPMFLOW_DATA to its data/ folder."
        )
    return path


def load(relative: str) -> NDArray[np.float64]:
    """A reference CSV (header line skipped) as a 2D array."""
    return np.loadtxt(data_dir() / relative, delimiter=",", skiprows=1, ndmin=2)


def errors_against_vof(
    t: Series, front: Series, height: Series, a: float, front_until: float, height_until: float
) -> dict[str, float]:
    """Largest |sim - VOF| / a of front (t <= front_until) and height (t <= height_until).

    The simulation series is interpolated linearly to the reference times."""
    ref = load(VOF_AR2)
    tr = ref[:, 0]
    out: dict[str, float] = {}
    for name, sim, col, until in (
        ("front", front, 1, front_until),
        ("height", height, 2, height_until),
    ):
        sel = tr <= until + 1e-9
        diff = np.interp(tr[sel], t, sim) - ref[sel, col]
        out[name] = float(np.max(np.abs(diff)) / a)
        out[name + "_rms"] = float(np.sqrt(np.mean(diff**2)) / a)
    return out


def height_error_against_martin_moyce(
    t: Series, height: Series, a: float, tau_until: float
) -> float:
    """Largest |sim - M&M Table 6| / a of the column height for tau = t sqrt(g/a) <= tau_until."""
    mm = load(MM_HEIGHT_AR2)
    sel = mm[:, 0] <= tau_until + 1e-9
    tau = np.asarray(t) * np.sqrt(G / a)
    diff = np.interp(mm[sel, 0], tau, height) - mm[sel, 1] * 2.0 * a
    return float(np.max(np.abs(diff)) / a)
