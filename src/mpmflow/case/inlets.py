"""The case's [[inlets]] tables: velocity inlets on the domain's sides (SI units: m, m/s),
and the rules between an inlet and the rest of the case."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Annotated

import numpy as np
from pydantic import Field, model_validator
from typing_extensions import Self

from .. import materials
from ..arrays import Floats
from .domain import AXES, Side
from .sections import Section

if TYPE_CHECKING:
    from .model import Case


class Inlet(Section):
    side: Side = Field(
        description="The side of the domain the water enters through: x_min, x_max (and "
        "y_min, y_max in 3D); not the floor or the ceiling (the last axis is up).",
        examples=["x_min"],
    )
    speed: float | None = Field(
        None,
        description="Speed (m/s) of the inflow, uniform over the opening and normal to the "
        "side, into the domain (or give profile). The side's nodes in the opening hold the "
        "water to it (a wall moving into the domain that never lets go), and each row of the "
        "particles' lattice across the opening adds a particle each time the inflow there "
        "has travelled one particle spacing: the volume that enters is the speed x the "
        "opening's area x time.",
        gt=0,
        examples=[0.5],
    )
    profile: list[Annotated[list[float], Field(min_length=2, max_length=2)]] | None = Field(
        None,
        description="A profiled inflow instead of speed: [[z, u], ...] pairs of height above "
        "the floor (m, increasing) and speed (m/s, >= 0), the speed at any height "
        "interpolated linearly between them and held at the end values beyond them; e.g. a "
        "power law tabulated, [[0.0, 0.0], [0.01, 0.35], [0.05, 0.48], [0.1, 0.5]].",
        min_length=1,
        examples=[[[0.0, 0.0], [0.05, 0.4], [0.1, 0.5]]],
    )
    level: float = Field(
        description="Top of the opening (m, along the last axis, from the floor): the water "
        "enters between the floor and this level, across the whole side. Rounded to the "
        "particles' lattice (a whole number of particle rows). Above it the side is the "
        "wall domain.walls gives it.",
        gt=0,
        examples=[0.1],
    )
    particles_per_cell: int = Field(
        2,
        ge=1,
        le=16,
        description="Material points per cell along each axis of the water the inlet brings "
        "(as bodies.N.particles_per_cell).",
    )

    @model_validator(mode="after")
    def _speed_or_profile(self) -> Self:
        if (self.speed is None) == (self.profile is None):
            raise ValueError(
                "give an inlet either speed (m/s, uniform) or profile ([[z, u], ...]), "
                "not both nor neither"
            )
        if self.profile is not None:
            z = [p[0] for p in self.profile]
            u = [p[1] for p in self.profile]
            if z[0] < 0 or any(b <= a for a, b in zip(z, z[1:])):
                raise ValueError(
                    f"profile heights {z} must start at or above the floor (0) and increase"
                )
            if min(u) < 0 or max(u) <= 0:
                raise ValueError(
                    f"profile speeds {u} must be >= 0 (into the domain), one of them > 0; "
                    "water leaves through an outlet"
                )
        return self

    def speed_at(self, z: Floats) -> Floats:
        """The inflow's speed (m/s) at heights z (m) above the floor."""
        if self.profile is None:
            return np.full(np.shape(z), float(self.speed or 0.0))
        table = np.asarray(self.profile, dtype=float)
        speed: Floats = np.interp(z, table[:, 0], table[:, 1])
        return speed

    @property
    def fastest(self) -> float:
        """The largest speed of the inflow (m/s)."""
        if self.profile is None:
            return float(self.speed or 0.0)
        return max(p[1] for p in self.profile)

    def spacing(self, grid_spacing: float) -> float:
        """The spacing (m) of the particles the inlet brings on a grid of ``grid_spacing``."""
        return grid_spacing / self.particles_per_cell

    def top(self, grid_spacing: float) -> float:
        """The opening's top (m): the level rounded down to whole rows of the particles'
        lattice."""
        s = self.spacing(grid_spacing)
        return math.floor(self.level / s + 1e-9) * s

    @property
    def axis(self) -> int:
        return AXES.index(self.side[0])

    @property
    def lower(self) -> bool:
        """Whether the side is at the axis's lower end (0), the flow towards +axis."""
        return self.side.endswith("_min")


def problem(case: Case) -> str | None:
    """What is wrong with the case's inlets (None: nothing)."""
    if not case.inlets:
        return None
    D = len(case.domain.size)
    if materials.is_solid(case.material):
        return (
            f'material.model = "{case.material.model}" is a solid; inlets bring a fluid (water '
            "or a viscous material): give a fluid material.model, or remove the [[inlets]]"
        )
    periodic = case.domain.periodic or [False] * D
    conditions = case.domain.wall_conditions()
    seen: set[str] = set()
    for k, inlet in enumerate(case.inlets):
        name = f"inlets.{k}"
        axis = inlet.axis
        if axis >= D:
            return f'{name}.side = "{inlet.side}" is not a side of a {D}D domain'
        if axis == D - 1:
            return (
                f'{name}.side = "{inlet.side}" is the floor or the ceiling; an inlet is a '
                f"side the water enters through sideways: give x_min or x_max"
                + (" (or y_min, y_max)" if D == 3 else "")
            )
        if periodic[axis]:
            return (
                f'{name}.side = "{inlet.side}": {AXES[axis]} is periodic (domain.periodic) and '
                "has no sides; make it a wall axis or move the inlet"
            )
        if conditions[axis][0 if inlet.lower else 1] == "outlet":
            return (
                f'{name}.side = "{inlet.side}" is an outlet in domain.walls; a side is one or '
                "the other: give the outlet another side"
            )
        if inlet.particles_per_cell != case.inlets[0].particles_per_cell:
            return (
                f"{name}.particles_per_cell = {inlet.particles_per_cell} differs from "
                f"inlets.0's {case.inlets[0].particles_per_cell}; the inlets share one lattice: "
                "give them the same particles_per_cell"
            )
        if inlet.side in seen:
            return f'two inlets on side "{inlet.side}"; give one inlet per side'
        seen.add(inlet.side)
        top = case.domain.size[D - 1]
        spacing = inlet.spacing(case.grid.spacing)
        if inlet.level > top * (1 + 1e-12):
            return (
                f"{name}.level = {inlet.level:g} m is above the domain's top ({top:g} m); "
                f"lower it or enlarge domain.size"
            )
        if inlet.level < spacing * (1 - 1e-9):
            return (
                f"{name}.level = {inlet.level:g} m is below one particle spacing "
                f"({spacing:g} m: grid.spacing / {name}.particles_per_cell); raise it"
            )
        if inlet.fastest > case.solver.max_speed:
            return (
                f"{name}'s speed {inlet.fastest:g} m/s is above solver.max_speed = "
                f"{case.solver.max_speed:g} m/s, the speed the run stops at; lower it or "
                "raise solver.max_speed"
            )
    return None
