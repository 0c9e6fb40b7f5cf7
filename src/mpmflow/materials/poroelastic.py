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

from typing import TYPE_CHECKING

from . import elastic

if TYPE_CHECKING:  # the case's schema lists the materials (case.sections imports this package)
    from ..case.sections import Material

NAME = "poroelastic"
KEYS: tuple[str, ...] = ("shear_modulus", "poisson_ratio", "permeability", "water_density")
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
