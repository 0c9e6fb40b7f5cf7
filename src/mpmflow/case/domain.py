"""The case's [domain] table: its size, the conditions of its walls (one for all, or per
side) and its periodic axes (SI units: m)."""

import difflib
from typing import Any, Literal, get_args

from pydantic import Field, ValidationInfo, field_validator, model_validator
from typing_extensions import Self

from .sections import Section

WALL_CONDITIONS = ("slip", "no_slip", "bonded", "outlet")
Condition = Literal["slip", "no_slip", "bonded", "outlet"]
AXES = "xyz"
SIDES = ("min", "max")  # the lower wall (at 0) and the upper (at domain.size)
# one side of the domain by name, in the order of Domain.outlet_sides
Side = Literal["x_min", "x_max", "y_min", "y_max", "z_min", "z_max"]
SIDE_NAMES: tuple[str, ...] = get_args(Side)


def wall_keys(dim: int) -> list[str]:
    """The keys of a per-side domain.walls: the axes, then each axis's two sides."""
    return [AXES[k] for k in range(dim)] + [f"{AXES[k]}_{s}" for k in range(dim) for s in SIDES]


class Domain(Section):
    size: list[float] = Field(
        description="Extent of the rectangular domain (m), one value per axis: 2 entries for "
        "a 2D case (x, y; y up), 3 for a 3D case (x, y, z; z up). The domain is [0, size]; "
        "its boundaries are walls. Every other vector of the case (bodies' min, max and "
        "velocity, gravity, probe positions) has as many entries.",
        examples=[[0.42, 0.44]],
        min_length=2,
        max_length=3,
    )
    walls: Condition | dict[str, Condition] = Field(
        "slip",
        description='Condition of the domain boundaries, "slip", "no_slip", "bonded" or '
        '"outlet": one for every side (walls = "no_slip"), or a table by axis and '
        "side: keys x, y (and z in 3D) set both walls across that axis, x_min, x_max, y_min, "
        "... one wall (min: at 0, max: at domain.size); a side's key overrides its axis's, "
        "and a wall left out is slip. E.g. a rough floor between smooth side walls in 3D: "
        'walls = {z_min = "no_slip"}; a flume with glass sides and a rough bed: '
        'walls = {y = "slip", z_min = "no_slip", x = "no_slip"}; one key on the '
        "command line: --set domain.walls.z_min=no_slip (over a single condition, it "
        "keeps that condition for the other walls). A periodic axis has no walls and "
        "takes no key. Walls are contact conditions: a wall holds the material where it "
        "presses against it and lets go where holding it would need suction while it "
        "moves away, so water falls from a ceiling and leaves a wall freely. no_slip also "
        "stops tangential motion where the wall holds (at an edge between a no-slip and a "
        "slip wall, the no-slip wall's hold). A bonded wall is a no-slip wall that never "
        "lets go: it holds the material at rest in tension too (a clamped end of a beam, a "
        "rough base that soil sticks to; one process only). An outlet is an open side, not a wall: the "
        "velocity there is free, the pressure takes the natural condition of the "
        "projection's weak form (no normal gradient: the flow leaves as if the domain went "
        "on), and the material that crosses it leaves the run (its particles removed, "
        "counted in summary.json's outflow); e.g. a channel's downstream end: "
        'walls = {x_max = "outlet"}. The projection scheme only; a periodic axis has none.',
    )
    periodic: list[bool] | None = Field(
        None,
        description="Periodic axes, one flag per axis (e.g. [true, false]: x wraps "
        "round): material leaving through one end of a periodic axis comes back through the "
        "other, and that axis has no walls. For channel and layer flows that are uniform "
        "along the axis. Along a periodic axis domain.size must be a whole, even number of "
        "grid cells, at least 4 (a power of two times a small number solves fastest); the "
        "projection scheme only.",
        examples=[[True, False]],
    )

    @field_validator("walls", mode="before")
    @classmethod
    def _wall_keys(cls, walls: Any, info: ValidationInfo) -> Any:
        dim = len(info.data.get("size") or ()) or 3
        keys = wall_keys(dim)
        example = '{z_min = "no_slip"}' if dim == 3 else '{y_min = "no_slip"}'
        if isinstance(walls, str):
            if walls not in WALL_CONDITIONS:
                raise ValueError(
                    f'{walls!r} is not a wall condition: give "slip", "no_slip", "bonded" or '
                    '"outlet" for every side, or a table of sides, e.g. '
                    f"walls = {example}"
                )
            return walls
        if not isinstance(walls, dict):
            raise ValueError(
                'give "slip", "no_slip" or "outlet" for every side, or a table of '
                f"sides, e.g. walls = {example}"
            )
        if not walls:
            raise ValueError(
                "the table of sides is empty; give at least one side, e.g. "
                f'walls = {example}, or "slip" for every wall'
            )
        for key, value in walls.items():
            if key not in keys:
                near = difflib.get_close_matches(str(key), keys, n=1, cutoff=0.5)
                hint = f" (did you mean {near[0]}?)" if near else ""
                raise ValueError(
                    f"{key!r} is not a side of a {dim}D domain{hint}; the keys are "
                    "the axes " + ", ".join(keys[:dim]) + " (both walls) and the "
                    "sides " + ", ".join(keys[dim:])
                )
            if value not in WALL_CONDITIONS:
                raise ValueError(
                    f"{key} = {value!r} is not a wall condition: give "
                    '"slip", "no_slip", "bonded" or "outlet"'
                )
        return walls

    @model_validator(mode="after")
    def _positive(self) -> Self:
        if any(s <= 0 for s in self.size):
            raise ValueError("every entry of domain.size must be positive (metres)")
        if self.periodic is not None and len(self.periodic) != len(self.size):
            raise ValueError(
                f"domain.periodic has {len(self.periodic)} entries and "
                f"domain.size {len(self.size)}; give one flag per axis, e.g. "
                f"periodic = {[True] + [False] * (len(self.size) - 1)}"
            )
        if isinstance(self.walls, dict):
            for k, flag in enumerate(self.periodic or []):
                named = [key for key in self.walls if key.split("_")[0] == AXES[k]]
                if flag and named:
                    raise ValueError(
                        f"domain.walls names {', '.join(named)}, but {AXES[k]} is periodic "
                        f"(domain.periodic), so it has no walls; remove "
                        f"{' and '.join(named)} from domain.walls, or make {AXES[k]} a wall "
                        "axis (domain.periodic)"
                    )
        return self

    def wall_conditions(self) -> list[tuple[str, str]]:
        """The condition of each wall, \"slip\" or \"no_slip\": a (lower, upper) pair per
        axis, the lower wall at 0 and the upper at domain.size (a periodic axis's pair too,
        though it has no walls)."""
        dim = len(self.size)
        if isinstance(self.walls, str):
            return [(self.walls, self.walls)] * dim
        out: list[tuple[str, str]] = []
        for k in range(dim):
            axis = self.walls.get(AXES[k], "slip")
            lower, upper = (self.walls.get(f"{AXES[k]}_{side}", axis) for side in SIDES)
            out.append((lower, upper))
        return out

    def walls_text(self) -> str:
        """domain.walls as a case file writes it: "no_slip", {x = "slip", z_min = ...}."""
        if isinstance(self.walls, str):
            return f'"{self.walls}"'
        return "{" + ", ".join(f'{k} = "{v}"' for k, v in self.walls.items()) + "}"

    def no_slip_sides(self) -> list[bool]:
        """One flag per wall in the order x_min, x_max, y_min, ... (the core's side order):
        whether it is no-slip."""
        return [c in ("no_slip", "bonded") for pair in self.wall_conditions() for c in pair]

    def bonded_sides(self) -> list[bool]:
        """One flag per wall in the order x_min, x_max, y_min, ...: whether it is bonded
        (no-slip, held in tension too)."""
        periodic = self.periodic or [False] * len(self.size)
        return [
            c == "bonded" and not periodic[k]
            for k, pair in enumerate(self.wall_conditions())
            for c in pair
        ]

    def outlet_sides(self) -> list[bool]:
        """One flag per side in the order x_min, x_max, y_min, ...: whether it is an outlet
        (never on a periodic axis)."""
        periodic = self.periodic or [False] * len(self.size)
        return [
            c == "outlet" and not periodic[k]
            for k, pair in enumerate(self.wall_conditions())
            for c in pair
        ]

    def uniform_walls(self) -> str | None:
        """The one condition of every wall (periodic axes and outlets aside), or None where
        walls differ."""
        periodic = self.periodic or [False] * len(self.size)
        found = {
            c
            for k, pair in enumerate(self.wall_conditions())
            if not periodic[k]
            for c in pair
            if c != "outlet"
        }
        if not found:  # every axis periodic or open: no walls at all
            return self.walls if self.walls in ("slip", "no_slip") else "slip"
        return found.pop() if len(found) == 1 else None
