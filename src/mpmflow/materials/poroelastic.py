"""A saturated soil (``material.model = "poroelastic"``): a linear elastic skeleton and
incompressible pore water flowing through it by Darcy's law, the pore pressure from the
projection (Kularathna et al. 2021; src/core/plasticity.hpp, POROELASTIC;
src/core/cell_pressure.hpp, darcy_*; docs/method.md, "Saturated soil").

The particles carry the mixture: its density is the saturated density, their stress the
effective stress sigma' (compression negative), their pressure the pore pressure, so the
total stress is sigma' - p I. The skeleton's stiffness is the drained one (shear modulus G
and Poisson's ratio nu); grains and water are incompressible, so the mixture changes its
volume only as water leaves it, and the step depends on neither the permeability nor a bulk
modulus of the water."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from ..arrays import Floats
from . import elastic

if TYPE_CHECKING:  # the case's schema lists the materials (case.sections imports this package)
    from ..case.sections import Material

NAME = "poroelastic"
KEYS: tuple[str, ...] = (
    "shear_modulus",
    "poisson_ratio",
    "permeability",
    "water_density",
    "initial_stress",
)
MODEL = 7  # src/core/plasticity.hpp's POROELASTIC (tests/materials check it against the core)
# standard gravity (m/s^2): a hydraulic conductivity k (m/s) is the water's mobility times its
# unit weight there, whatever the case's gravity (a weightless consolidation test has none)
STANDARD_GRAVITY = 9.80665


def lame(m: Material) -> float:
    """The drained skeleton's first Lame constant lambda = 2 G nu / (1 - 2 nu) (Pa)."""
    return 2.0 * m.shear_modulus * m.poisson_ratio / (1.0 - 2.0 * m.poisson_ratio)


def constrained_modulus(m: Material) -> float:
    """The drained skeleton's one-dimensional (oedometric) modulus lambda + 2 G (Pa)."""
    return lame(m) + 2.0 * m.shear_modulus


def mobility(m: Material) -> float:
    """The pore water's mobility k / (rho_w g_n) (m^2/(Pa s)): Darcy's flux per pressure
    gradient."""
    return m.permeability / (m.water_density * STANDARD_GRAVITY)


def consolidation_coefficient(m: Material) -> float:
    """Terzaghi's coefficient of consolidation c_v = k M / (rho_w g_n) (m^2/s), M the
    constrained modulus."""
    return mobility(m) * constrained_modulus(m)


def check(m: Material) -> None:
    elastic.check_shear_modulus(m)
    if not 0.0 <= m.poisson_ratio < 0.5:
        raise ValueError(
            f"material.poisson_ratio = {m.poisson_ratio:g}: the drained skeleton's Poisson's "
            'ratio of model = "poroelastic" must lie in [0, 0.5) (soils: 0.2 to 0.35); an '
            'incompressible skeleton (0.5) is model = "elastic"'
        )
    if not m.permeability > 0.0:
        raise ValueError(
            f"material.permeability = {m.permeability:g}: the hydraulic conductivity k (m/s) "
            'of model = "poroelastic" must be > 0 (clay 1e-9, silt 1e-7, sand 1e-4); an '
            'undrained soil that never drains is model = "elastic"'
        )
    if not 0.0 < m.water_density < m.density:
        raise ValueError(
            f"material.water_density = {m.water_density:g} kg/m^3 must be > 0 and below the "
            f"saturated soil's material.density ({m.density:g} kg/m^3), e.g. 1000"
        )


def parameters(m: Material) -> list[float]:
    return [m.shear_modulus, lame(m), mobility(m), m.water_density]


def free_water(m: Material, mass: Floats, volume: Floats) -> np.ndarray:
    """Which particles are free water: those of the water's density (src/core/plasticity.hpp,
    free_water; the mixture is denser, which ``check`` holds)."""
    return np.asarray(mass <= m.water_density * volume * (1 + 1e-9))


def geostatic_problem(gravity: Sequence[float]) -> str | None:
    """Why a geostatic start cannot be taken under this gravity (None: it can): the
    skeleton's weight is taken down the last axis."""
    if any(c != 0.0 for c in gravity[:-1]) or not gravity[-1] < 0.0:
        return (
            'material.initial_stress = "geostatic" needs physics.gravity down the last axis '
            f"(its other components 0), not {list(gravity)}: the skeleton's weight is taken "
            'along it; or give material.initial_stress = "zero"'
        )
    return None


def geostatic_stress(
    m: Material, x: Floats, mass: Floats, volume: Floats, gravity: Floats
) -> Floats:
    """The effective stress (count x D x D, Pa) of the skeleton at rest under its buoyant
    weight (``initial_stress = "geostatic"``): sigma'_v = -(density - water_density) |g| d
    along the last axis, d the depth below the soil's top in the particle's column (the
    highest soil particle's centre plus half a particle spacing, spacing = volume^(1/D)),
    sigma'_h = nu / (1 - nu) sigma'_v on the other axes; zero in free water. Gravity must
    point down the last axis (ValueError: ``geostatic_problem``)."""
    n, D = x.shape
    g = np.asarray(gravity, dtype=float)
    problem = geostatic_problem(list(g))
    if problem:
        raise ValueError(problem)
    stress = np.zeros((n, D, D))
    soil = ~free_water(m, mass, volume)
    if not soil.any():
        return stress
    spacing = volume[soil] ** (1.0 / D)
    key = np.round(x[soil, :-1] / (0.5 * spacing.min())).astype(np.int64)
    _, column = np.unique(key, axis=0, return_inverse=True)
    column = column.ravel()
    top = np.full(column.max() + 1, -np.inf)
    np.maximum.at(top, column, x[soil, -1] + 0.5 * spacing)
    depth = top[column] - x[soil, -1]
    vertical = -(m.density - m.water_density) * -g[-1] * depth
    k0 = m.poisson_ratio / (1.0 - m.poisson_ratio)
    for k in range(D - 1):
        stress[soil, k, k] = k0 * vertical
    stress[soil, D - 1, D - 1] = vertical
    return stress


def darcy_flux(
    m: Material,
    spacing: float,
    cells: tuple[int, ...],
    p_node: Floats,
    x: Floats,
    mass: Floats,
    volume: Floats,
    gravity: Floats,
) -> Floats:
    """The pore water's flux relative to the skeleton at each particle (count x D, m/s):
    Darcy's q = n (v_w - v) = -k / (rho_w g_n) (grad p - rho_w g), grad p the multilinear
    gradient of the nodal pore pressure (``p_node``, Pa, the nodes in flat order, x fastest)
    at the particle; 0 in free water, which moves with its own velocity."""
    n, D = x.shape
    h = float(spacing)
    nodes = [c + 1 for c in cells]
    stride = np.cumprod([1, *nodes[:-1]])
    s = x / h
    base = np.clip(np.floor(s).astype(np.int64), 0, np.asarray(cells) - 1)
    frac = s - base
    grad = np.zeros((n, D))
    for corner in range(2**D):
        bits = [(corner >> k) & 1 for k in range(D)]
        p = p_node[(base + np.asarray(bits)) @ stride]
        for j in range(D):
            w = np.full(n, (1.0 if bits[j] else -1.0) / h)
            for k in range(D):
                if k != j:
                    w *= frac[:, k] if bits[k] else 1.0 - frac[:, k]
            grad[:, j] += w * p
    q = -mobility(m) * (grad - m.water_density * np.asarray(gravity, dtype=float))
    q[free_water(m, mass, volume)] = 0.0
    return q
