"""The case's [[loads]] tables: tractions on faces of the material (SI units: m, Pa), a
consolidation test's surface load. Each load acts on the grid's nodes of one node plane, each
node taking the traction times its share of the face (boundaries/loads.py). And the
[plate]: a rigid plate on a wall pressed on a saturated soil with a given force (Mandel's
problem; src/core/step.hpp, State::set_plate)."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Literal

from pydantic import Field

from .. import materials
from .domain import AXES, SIDE_NAMES, Side
from .sections import Section

if TYPE_CHECKING:
    from .model import Case


class Load(Section):
    axis: Literal["x", "y", "z"] = Field(
        description="The axis normal to the loaded face: a face of constant x, y or z.",
        examples=["y"],
    )
    at: float = Field(
        description="Where the face lies along the axis (m): a plane of the grid's nodes, a "
        "multiple of grid.spacing, at the material's surface (a column's top). The load acts "
        "on the nodes there as long as material reaches them: the run stops if the face "
        "moves off the nodes (a settlement past a cell).",
        examples=[1.0],
    )
    lower: list[float] = Field(
        description="The face's lower corner along the other axes, in their order (m; one "
        "value in 2D, two in 3D).",
        examples=[[0.0]],
    )
    upper: list[float] = Field(
        description="The face's upper corner along the other axes (m).", examples=[[0.2]]
    )
    traction: list[float] = Field(
        description="The traction (Pa), the force per unit area of the face on the material, "
        "one component per axis: [0, -1e4] presses down on a top face with 10 kPa. It is "
        "applied in full from the first step (a sudden load).",
        examples=[[0.0, -1e4]],
    )


class Plate(Section):
    side: Side = Field(
        description="The wall the plate lies on: the material there is held to the plate's "
        "one velocity along the side's axis (its other components free: frictionless), and no "
        "water flows through it (impermeable).",
        examples=["y_max"],
    )
    force: float = Field(
        description="The plate's total force on the material along the side's axis (N; "
        "2D: N per m of depth), positive along the axis: a plate on y_max pressing down "
        "with 20 kN/m is -2e4. Applied in full from the first step, held constant; the "
        "plate's velocity is whatever makes the material's reaction meet it each step.",
        examples=[-2e4],
    )


def plate_problem(case: Case) -> str | None:
    """What is wrong with the case's plate (None: nothing or no plate)."""
    plate = case.plate
    if plate is None:
        return None
    D = len(case.domain.size)
    k = SIDE_NAMES.index(plate.side) // 2
    if k >= D:
        return f'plate.side = "{plate.side}" is not a side of a {D}D domain'
    if case.material.model not in materials.SATURATED:
        return (
            f'plate: a rigid plate presses a saturated soil (material.model = "poroelastic"), '
            f"not material.model = {case.material.model!r}; remove the [plate], or use "
            "[[loads]] for a traction"
        )
    periodic = case.domain.periodic or [False] * D
    if periodic[k]:
        return f'plate.side = "{plate.side}": that axis is periodic and has no walls'
    if case.domain.outlet_sides()[SIDE_NAMES.index(plate.side)]:
        return f'plate.side = "{plate.side}" is an outlet; the plate needs a wall there'
    if not math.isfinite(plate.force):
        return "plate.force must be finite (N; 2D N/m)"
    return None


def problem(case: Case) -> str | None:
    """What is wrong with the case's loads (None: nothing)."""
    D = len(case.domain.size)
    h = case.grid.spacing
    periodic = case.domain.periodic or [False] * D
    for n, load in enumerate(case.loads):
        name = f"loads.{n}"
        k = AXES.index(load.axis)
        if k >= D:
            return f'{name}.axis = "{load.axis}" is not an axis of a {D}D domain: give x or y'
        others = [m for m in range(D) if m != k]
        if len(load.lower) != D - 1 or len(load.upper) != D - 1:
            return (
                f"{name}.lower and .upper need {D - 1} value(s) each, the face's extent along "
                f"{', '.join(AXES[m] for m in others)} (m)"
            )
        if len(load.traction) != D:
            return f"{name}.traction needs {D} components (Pa), one per axis"
        if not all(math.isfinite(t) for t in load.traction):
            return f"{name}.traction must be finite (Pa)"
        if any(periodic):
            return f"{name}: loads are not applied on a periodic domain yet; remove the load"
        size = case.domain.size[k]
        j = load.at / h
        if not (0.0 <= load.at <= size) or abs(j - round(j)) > 1e-6:
            below = math.floor(j) * h
            return (
                f"{name}.at = {load.at:g} m must be a plane of the grid's nodes within the "
                f"domain (a multiple of grid.spacing = {h:g} m, 0 to {size:g}); the nearest "
                f"are {below:g} and {below + h:g} m"
            )
        for i, m in enumerate(others):
            lo, hi = load.lower[i], load.upper[i]
            if not 0.0 <= lo < hi <= case.domain.size[m]:
                return (
                    f"{name}.lower[{i}] = {lo:g} and .upper[{i}] = {hi:g} m must give an "
                    f"extent along {AXES[m]} within the domain (0 to "
                    f"{case.domain.size[m]:g} m), lower below upper"
                )
    return None
