"""The case's [[sponges]] tables: damping zones along the domain's sides (a numerical beach),
where the water's velocity is relaxed towards rest (SI units: m, 1/s)."""

from __future__ import annotations

from typing import TYPE_CHECKING, Literal

from pydantic import Field

from .sections import Section

if TYPE_CHECKING:
    from .model import Case

AXIS = {"x_min": 0, "x_max": 0, "y_min": 1, "y_max": 1}


class Sponge(Section):
    side: Literal["x_min", "x_max", "y_min", "y_max"] = Field(
        description="The side of the domain the zone lies along: x_min, x_max (and y_min, "
        "y_max in 3D); not the floor or the ceiling (the last axis is up). Waves and the "
        "flow that enter the zone are damped out instead of reflected by the wall.",
        examples=["x_max"],
    )
    length: float = Field(
        gt=0,
        description="Width (m) of the zone, from the side inwards: a wave is absorbed with "
        "little reflection when this is about a wavelength or more.",
        examples=[1.0],
    )
    strength: float = Field(
        10.0,
        gt=0,
        description="Largest damping rate c (1/s), at the side: the predictor's velocity is "
        "divided by 1 + c(x) dt each step, with c rising from 0 at the zone's inner edge as "
        "the square of the distance into it (a gradual rise reflects least).",
    )


def problem(case: Case) -> str | None:
    """What is wrong with the case's sponges (None: nothing)."""
    D = len(case.domain.size)
    periodic = case.domain.periodic or [False] * D
    for k, sponge in enumerate(case.sponges):
        axis = AXIS[sponge.side]
        if axis == D - 1:
            return (
                f'sponges.{k}.side = "{sponge.side}" is the floor or the ceiling of a {D}D '
                "domain; a sponge lies along a side the waves run into: give x_min or x_max"
                + (" (or y_min, y_max)" if D == 3 else "")
            )
        if periodic[axis]:
            return (
                f'sponges.{k}.side = "{sponge.side}": that axis is periodic '
                "(domain.periodic) and has no sides; remove the sponge or the periodicity"
            )
        if sponge.length > case.domain.size[axis]:
            return (
                f"sponges.{k}.length = {sponge.length:g} m is longer than the domain along "
                f"that axis ({case.domain.size[axis]:g} m); give a shorter zone"
            )
    return None
