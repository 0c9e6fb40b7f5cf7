"""A viscoplastic (yield-stress) material, Herschel-Bulkley (``material.model =
"herschel_bulkley"``; Bingham when flow_index = 1): |tau| = yield_stress + consistency
rate^flow_index where it flows, rigid below the yield stress. Regularised as the bi-viscous
model: eta = min(max_viscosity, consistency rate^(n - 1) + yield_stress / rate), so below
the yield stress the material creeps at rate |tau| / max_viscosity."""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:  # the case's schema lists the materials (case.sections imports this package)
    from ..case.sections import Material

NAME = "herschel_bulkley"
KEYS: tuple[str, ...] = ("consistency", "yield_stress", "flow_index", "max_viscosity")
MODEL = 2  # src/core/rheology.hpp's HERSCHEL_BULKLEY (tests/materials check it against the core)


def check(m: Material) -> None:
    if not m.consistency > 0.0:
        raise ValueError(
            'material.model = "herschel_bulkley" needs material.consistency > 0 '
            "(Pa s^n; the plastic viscosity of a Bingham material), e.g. "
            "material.consistency = 1.0"
        )
    if m.yield_stress < 0.0:
        raise ValueError(
            f"material.yield_stress = {m.yield_stress:g} Pa is negative: give "
            "the yield stress in Pa, >= 0 (0 is a power-law liquid)"
        )
    if not m.flow_index > 0.0:
        raise ValueError(
            f"material.flow_index = {m.flow_index:g} must be positive (1 is "
            "Bingham; < 1 shear-thinning, > 1 shear-thickening)"
        )
    if not m.max_viscosity > m.consistency:
        raise ValueError(
            f"material.max_viscosity = {m.max_viscosity:g} Pa s must be larger "
            f"than material.consistency = {m.consistency:g}: it caps the "
            "viscosity of the unyielded material (e.g. 1000 times the "
            "consistency)"
        )


def parameters(m: Material) -> list[float]:
    return [m.consistency, m.yield_stress, m.flow_index, m.max_viscosity]
