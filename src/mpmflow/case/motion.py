"""The prescribed motion of an obstacle (``obstacles.N.motion``): a body that moves as a given
function of time (a footing pushed down, a gate lifted, a piston or flap wave maker).
``boundaries.moving`` turns it into the path the compiled step follows."""

from typing import Literal

from pydantic import Field, model_validator
from typing_extensions import Self

from .sections import Section

MOTION_TYPES = ("velocity", "oscillation", "table", "free")
DOF_NAMES = {2: ("x", "y", "rotation"), 3: ("x", "y", "z", "rx", "ry", "rz")}


class Motion(Section):
    type: Literal["velocity", "oscillation", "table", "free"] = Field(
        description='How the obstacle moves: "velocity" (a constant velocity and turning '
        'rate from `start` to `stop`), "oscillation" (x(t) = amplitude sin(2 pi t / '
        "period), angle(t) = angle_amplitude sin(2 pi t / period), each times a ramp that "
        'rises from 0 to 1 over `ramp` seconds: a piston or flap wave maker), "table" '
        '(displacement and angle read from a CSV file, `file`) or "free" (a rigid body '
        "moved by gravity and the water's pressure, of `density` or `mass`, starting at "
        "`velocity`; `locked` holds some of its degrees of freedom)."
    )
    velocity: list[float] | None = Field(
        None,
        description='Velocity (m/s) of the obstacle\'s pivot, type = "velocity" (one entry '
        "per axis; none: it only turns).",
        min_length=2,
        max_length=3,
    )
    rate: float = Field(
        0.0,
        description="Turning rate (degrees/s, counter-clockwise about `axis`) about the pivot, "
        'type = "velocity".',
    )
    start: float = Field(
        0.0, ge=0, description='Time (s) the motion starts, type = "velocity" (at rest before).'
    )
    stop: float | None = Field(
        None,
        description='Time (s) the motion stops, type = "velocity" (at rest after; none: '
        "it goes on to the end of the run).",
    )
    amplitude: list[float] | None = Field(
        None,
        description='Displacement amplitude (m) along each axis, type = "oscillation" (a '
        "piston's stroke is twice it; none: it only turns).",
        min_length=2,
        max_length=3,
    )
    angle_amplitude: float = Field(
        0.0, description='Amplitude (degrees) of the turning about the pivot, type = "oscillation".'
    )
    period: float | None = Field(None, gt=0, description='Period (s), type = "oscillation".')
    ramp: float = Field(
        0.0,
        ge=0,
        description='Time (s) over which an oscillation\'s amplitude (type = "oscillation"), '
        'or the velocity (type = "velocity", from `start`), rises smoothly from 0 '
        "(0.5 (1 - cos(pi t / ramp))); 0: at once.",
    )
    file: str | None = Field(
        None,
        description='CSV file of the path, type = "table", relative to the case file: a '
        "header line, then rows t (s), the displacement along each axis (m; x, y in 2D; x, "
        "y, z in 3D) and optionally the angle (degrees about the pivot and axis); times "
        "increasing, from 0 to at least time.end. Velocities are the table's second-order "
        "differences.",
    )
    pivot: list[float] | None = Field(
        None,
        description="The point (m, at t = 0) the obstacle turns about and whose displacement "
        "the motion gives; none: the centre of the obstacle's bounding box (a free body: its "
        "centroid). A free body with a pivot elsewhere is hinged there: hold its translations "
        '(locked = ["x", "y"], 3D also "z" and two of the rotations).',
        min_length=2,
        max_length=3,
    )
    axis: list[float] = Field(
        [0.0, 0.0, 1.0],
        description="The axis the obstacle turns about (3D; any length; a 2D case turns in "
        "its plane, about z).",
        min_length=3,
        max_length=3,
    )

    density: float | None = Field(
        None,
        gt=0,
        description='Density (kg/m^3) of a free body (type = "free"): its mass and inertia '
        "from its shape (2D: per metre of depth).",
    )
    mass: float | None = Field(
        None,
        gt=0,
        description='Mass (kg; 2D kg per metre of depth) of a free body (type = "free"), '
        "instead of its density: its inertia from its shape at the density this gives.",
    )
    friction: float = Field(
        0.0,
        ge=0,
        description='Coulomb friction coefficient mu of a free body (type = "free") where it '
        "touches a wall, an obstacle or another body: the contact's tangential impulse stops "
        "the sliding up to mu times its normal impulse (between two free bodies mu is the "
        "geometric mean of theirs). 0: frictionless (the default).",
    )
    locked: list[Literal["x", "y", "z", "rotation", "rx", "ry", "rz"]] = Field(
        [],
        description='Degrees of freedom a free body keeps at their start (type = "free"): '
        '"x", "y" (and "z") its pivot\'s motion along the axes, "rotation" (2D) or "rx", '
        '"ry", "rz" (3D) its turning about them; e.g. ["x", "rotation"] lets a 2D body '
        "heave only.",
    )

    @model_validator(mode="after")
    def _complete(self) -> Self:
        if self.type == "oscillation" and self.period is None:
            raise ValueError('type = "oscillation" needs its period (s): give period = ...')
        if self.type == "table" and not self.file:
            raise ValueError('type = "table" needs the CSV file of its path: give file = "..."')
        if self.stop is not None and not self.stop > self.start:
            raise ValueError(f"stop = {self.stop} s must come after start = {self.start} s")
        if self.type == "free" and (self.density is None) == (self.mass is None):
            raise ValueError(
                'type = "free" needs the body\'s density (kg/m^3) or its mass (kg), one of '
                "them: give density = ... or mass = ..."
            )
        if self.type != "free" and (self.density or self.mass or self.locked or self.friction):
            raise ValueError(
                f'density, mass, locked and friction are for type = "free"; type = '
                f'"{self.type}" follows its path whatever its mass: remove them'
            )
        if not any(self.axis):
            raise ValueError("axis must not be [0, 0, 0]; give the direction, e.g. [0, 1, 0]")
        return self
