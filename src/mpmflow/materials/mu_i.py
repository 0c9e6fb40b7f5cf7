"""Dense granular flow with the mu(I) rheology (``material.model = "mu_i"``; Jop,
Forterre & Pouliquen 2006): |tau| = mu(I) p with mu(I) = mu_s + (mu_2 - mu_s) / (I0 / I + 1)
and the inertial number I = rate d / sqrt(p / rho_s), incompressible at the solid fraction
phi = material.density / material.grain_density. As a viscosity: eta = mu(I) p / rate,
capped at max_viscosity (at rest the material creeps at rate |tau| / max_viscosity); no
strength without pressure (p <= 0: eta = 0)."""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:  # the case's schema lists the materials (case.sections imports this package)
    from ..case.sections import Material

NAME = "mu_i"
KEYS: tuple[str, ...] = (
    "friction_static",
    "friction_limit",
    "inertial_number_ref",
    "grain_diameter",
    "grain_density",
    "max_viscosity",
)
MODEL = 3  # src/core/rheology.hpp's MU_I (tests/materials check it against the core)


def check(m: Material) -> None:
    if not 0.0 < m.friction_static < m.friction_limit:
        raise ValueError(
            f"material.friction_static = {m.friction_static:g} and material.friction_limit "
            f"= {m.friction_limit:g}: mu(I) needs 0 < mu_s < mu_2 (glass beads, Jop et al. "
            "2006: friction_static = 0.38, friction_limit = 0.64)"
        )
    if not m.inertial_number_ref > 0.0:
        raise ValueError("material.inertial_number_ref (I0) must be positive (glass beads: 0.279)")
    if not m.grain_diameter > 0.0:
        raise ValueError(
            "material.grain_diameter must be positive (m; glass beads of Jop et al. 2006: 0.53e-3)"
        )
    if not m.grain_density >= m.density:
        raise ValueError(
            f"material.grain_density = {m.grain_density:g} kg/m^3 is below material.density "
            f"= {m.density:g} kg/m^3: with mu(I), density is the bulk density, solid "
            "fraction x grain density (e.g. 0.6 x 2450 = 1470), so the solid fraction "
            "density / grain_density must be at most 1"
        )
    if not m.max_viscosity > 0.0:
        raise ValueError("material.max_viscosity must be positive (Pa s)")


def parameters(m: Material) -> list[float]:
    return [
        m.friction_static,
        m.friction_limit,
        m.inertial_number_ref,
        m.grain_diameter,
        m.grain_density,
        m.max_viscosity,
    ]
