"""The analytic channel flows the validation compares with (SI units): plane Poiseuille
(start-up series and steady profile), the Bingham plug, the inclined mu(I) layer with
Bagnold's profile; and the binning of particle velocities across the layer."""

import math
from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..case import Case
from .common import box
from .types import FloatArray

SERIES_TERMS = 200  # of the start-up series: the tail after N terms is below 1 / (pi^3 N^2)


# --- analytic solutions -----------------------------------------------------------------


def poiseuille(
    y: ArrayLike, H: float, nu: float, gs: float, t: float | None = None, terms: int = SERIES_TERMS
) -> FloatArray:
    """The film's velocity (m/s) at heights ``y`` (m) above the no-slip bed: the steady
    half-channel profile (t None), or the start-up from rest at time ``t`` (s) as the
    Fourier series of the half-channel (no slip at y = 0, no shear at y = H). ``gs``: the
    driving acceleration g sin(theta) (m/s^2); ``nu``: kinematic viscosity (m^2/s)."""
    e = np.clip(np.asarray(y, float) / H, 0.0, 1.0)
    u = e - 0.5 * e * e
    if t is not None:
        for n in range(terms):
            lam = (n + 0.5) * math.pi
            u = u - 2.0 / lam**3 * np.sin(lam * e) * math.exp(-lam * lam * nu * t / (H * H))
    return gs * H * H / nu * u


def plug_width(H: float, rho: float, tau_y: float, gs: float) -> float:
    """The Bingham plug's thickness (m): where the shear stress rho gs (H - y) < tau_y."""
    return min(H, tau_y / (rho * gs))


def bingham(y: ArrayLike, H: float, rho: float, K: float, tau_y: float, gs: float) -> FloatArray:
    """The steady Bingham layer's velocity (m/s): the yielded layer's parabola below
    Y = H - h_p, the plug's speed rho gs Y^2 / (2 K) above."""
    Y = H - plug_width(H, rho, tau_y, gs)
    yy: FloatArray = np.clip(np.asarray(y, float), 0.0, Y)
    return rho * gs / K * (Y * yy - 0.5 * yy * yy)


def inertial_number(theta: float, mu_s: float, mu_2: float, I0: float) -> float:
    """The inertial number of steady flow at inclination ``theta`` (rad): mu(I) = tan(theta)
    with mu(I) = mu_s + (mu_2 - mu_s) I / (I0 + I); nan outside mu_s < tan(theta) < mu_2."""
    t = math.tan(theta)
    if not mu_s < t < mu_2:
        return float("nan")
    return I0 * (t - mu_s) / (mu_2 - t)


def bagnold(
    y: ArrayLike,
    H: float,
    theta: float,
    mu_s: float,
    mu_2: float,
    I0: float,
    d: float,
    phi: float,
    g: float = 9.81,
) -> FloatArray:
    """Bagnold's profile (m/s) of a mu(I) layer H deep at inclination ``theta``: grain
    diameter d (m), solid fraction phi = bulk density / grain density."""
    It = inertial_number(theta, mu_s, mu_2, I0)
    depth: FloatArray = np.clip(H - np.asarray(y, float), 0.0, H)
    u: FloatArray = (
        (2.0 / 3.0) * It * math.sqrt(phi * g * math.cos(theta)) / d * (H**1.5 - depth**1.5)
    )
    return u


# --- measures -----------------------------------------------------------------------------


def incline(case: Case) -> tuple[float, float]:
    """(theta (rad), |g|) of a case's tilted gravity [g sin(theta), -g cos(theta)]."""
    gx, gy = case.physics.gravity[:2]
    return math.atan2(gx, -gy), math.hypot(gx, gy)


def depth(case: Case) -> float:
    """The layer's initial depth H (m): the height of the case's first body, a box."""
    column = box(case.bodies[0])
    return float(column.max[1] - column.min[1])


def bins(y: ArrayLike, H: float, h: float) -> tuple[NDArray[np.int_], int]:
    """Index of each particle's bin (one cell high, 0 < y < H; -1 outside) and their count."""
    n = int(round(H / h))
    idx = np.floor(np.asarray(y) / h).astype(int)
    idx[(idx < 0) | (idx >= n)] = -1
    return idx, n


def binned(
    y: FloatArray, u: FloatArray, H: float, h: float, theory: Callable[[FloatArray], FloatArray]
) -> tuple[FloatArray, ...]:
    """(mean height, mean u, mean theory) per bin (arrays; empty bins dropped)."""
    idx, n = bins(y, H, h)
    th = theory(y)
    out = []
    for b in range(n):
        s = idx == b
        if s.any():
            out.append((y[s].mean(), u[s].mean(), th[s].mean()))
    return tuple(np.array(c) for c in zip(*out))


def l2(um: FloatArray, ut: FloatArray) -> float:
    return float(math.sqrt(np.sum((um - ut) ** 2) / np.sum(ut**2)))


def fit_plug(y: FloatArray, u: FloatArray, H: float, h: float) -> float:
    """The plug width (m): H - Y of the Bingham profile A (Y y - y^2 / 2) (y < Y),
    A Y^2 / 2 (y > Y) fitted by least squares to the binned velocity (A linear in the
    fit; Y scanned over [0.05 H, H] then refined by a bounded scalar minimisation)."""
    from scipy.optimize import minimize_scalar

    idx, n = bins(y, H, h)
    keep = idx >= 0
    idx, yk, uk = idx[keep], y[keep], u[keep]
    count = np.bincount(idx, minlength=n).astype(float)
    filled = count > 0
    ub = (np.bincount(idx, uk, minlength=n) / np.maximum(count, 1))[filled]

    def residual(Y: float) -> float:
        z = np.minimum(yk, Y)
        f = (np.bincount(idx, Y * z - 0.5 * z * z, minlength=n) / np.maximum(count, 1))[filled]
        A = float(f @ ub) / float(f @ f)
        return float(np.sum((A * f - ub) ** 2))

    grid = np.linspace(0.05 * H, H, 200)
    k = int(np.argmin([residual(Y) for Y in grid]))
    lo, hi = grid[max(k - 1, 0)], grid[min(k + 1, len(grid) - 1)]
    Y = minimize_scalar(residual, bounds=(lo, hi), method="bounded", options={"xatol": 1e-7 * H}).x
    return float(H - Y)
