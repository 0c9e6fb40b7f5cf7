"""Materials by name (``material.model``), one module each, as the schemes are.

A material module gives:

* ``NAME``: its name, the value of ``material.model``;
* ``KEYS``: the ``[material]`` keys that are its parameters (besides ``density`` and
  ``bulk_modulus``, which every material has); the schema (``mpmflow.case.sections.Material``)
  holds their descriptions and units;
* ``MODEL``: its code in the compiled rheology (src/core/rheology.hpp), as a number, so that
  the case's schema reads the materials without loading the compiled core;
* ``check(m)``: the checks of its parameters, raising ValueError with a message that names
  the key and the fix;
* ``parameters(m)``: its parameters as the float array the compiled rheology reads.

A material is one per case for now; the compiled step takes (model, parameters) so that a
table of materials indexed per particle can follow without changing the kernels' formulas.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Protocol

import numpy as np

from ..arrays import Floats
from . import (
    drucker_prager,
    elastic,
    herschel_bulkley,
    mu_i,
    newtonian,
    poroelastic,
    von_mises,
    water,
)

if TYPE_CHECKING:  # the case's schema lists the materials (case.sections imports this package)
    from ..case.sections import Material


class Model(Protocol):
    """What a material module gives (see above); the modules are checked against it."""

    NAME: str
    KEYS: tuple[str, ...]
    MODEL: int

    def check(self, m: Material) -> None: ...

    def parameters(self, m: Material) -> list[float]: ...


_MODULES: tuple[Model, ...] = (
    water,
    newtonian,
    herschel_bulkley,
    mu_i,
    elastic,
    von_mises,
    drucker_prager,
    poroelastic,
)
# the solids: a stress history on the particles (src/core/plasticity.hpp), no viscous solve
SOLIDS = frozenset({elastic.NAME, von_mises.NAME, drucker_prager.NAME, poroelastic.NAME})
# a saturated soil: its pore water flows through the skeleton (Darcy), the pore pressure the
# projection's (src/core/cell_pressure.hpp, darcy_*)
SATURATED = frozenset({poroelastic.NAME})
# the solids whose strength reads the pressure (a frictional soil)
FRICTIONAL = frozenset({drucker_prager.NAME})
MATERIALS: dict[str, Model] = {m.NAME: m for m in _MODULES}
COMMON = ("model", "density", "bulk_modulus")


def check(m: Material) -> None:
    """Refuse parameters of another model (set to other than their defaults), then run the
    model's own checks."""
    module = MATERIALS[m.model]
    for key in sorted(m.model_fields_set):
        # a key at its default is not in the way (a resolved case lists every key)
        if (
            key in COMMON
            or key in module.KEYS
            or getattr(m, key) == type(m).model_fields[key].default
        ):
            continue
        owners = [n for n, mod in MATERIALS.items() if key in mod.KEYS]
        takes = ", ".join(module.KEYS) if module.KEYS else "no parameters besides density"
        raise ValueError(
            f"material.{key} is a parameter of material.model = "
            f"{' or '.join(repr(o) for o in owners)}, not of {m.model!r} (which takes "
            f"{takes}): remove it, or set material.model to the model it belongs to"
        )
    module.check(m)


def parameters(m: Material) -> tuple[int, Floats]:
    """(model code, parameters) for the compiled step."""
    module = MATERIALS[m.model]
    return module.MODEL, np.asarray(module.parameters(m), dtype=float)


def is_viscous(m: Material) -> bool:
    return m.model not in SOLIDS and MATERIALS[m.model].MODEL != water.MODEL


def is_solid(m: Material) -> bool:
    return m.model in SOLIDS


def viscous_solve(m: Material) -> bool:
    """Whether the predictor runs the implicit viscous solve: a viscous material's, and a
    solid's implicit elastic predictor (eta = G dt; src/core/step.cpp, viscous_start)."""
    return is_viscous(m) or is_solid(m)


# a solid's step, as a fraction of the time a shear wave takes to cross a cell: the longest
# time.dt = "auto" takes (the waves are followed: a layer's period within 0.1% at H / 20),
# and past which a fixed time.dt takes the coupled step (the elastic solve and the
# projection as one system: their split grew a swinging cantilever at 1.5 in 2D, crept at
# 0.7 in 3D and broke down there at 1.0; docs/method.md, "Solids")
SHEAR_COURANT = 0.5


def shear_wave_step(m: Material, spacing: float) -> float:
    """A solid's step (s) on cells of side ``spacing`` (m): SHEAR_COURANT h / sqrt(G /
    density), the longest time.dt = "auto" takes and past which a fixed one takes the
    coupled step; inf for a fluid."""
    if not is_solid(m):
        return float("inf")
    return float(SHEAR_COURANT * spacing / (m.shear_modulus / m.density) ** 0.5)


def coupled_step(m: Material, spacing: float, dt: float) -> bool:
    """Whether steps of dt (s) on cells of side ``spacing`` (m) take a solid's coupled step
    (the elastic solve and the projection as one system: past ``shear_wave_step``), and
    every step of a saturated soil, whose consolidation takes steps far past it."""
    if m.model in SATURATED:
        return True
    return dt > shear_wave_step(m, spacing) * (1 + 1e-9)
