"""The shapes of bodies and obstacles in the case file: one model per shape type holding
only the shape's fields; bodies and obstacles add their own fields to the same shape
classes (``mpmflow.geometry`` builds the geometry from them)."""

from typing import Annotated, Any, ClassVar, Literal

from pydantic import Discriminator, Field, Tag, field_validator, model_validator
from typing_extensions import Self

from ..geometry import shapes
from .motion import Motion
from .sections import Section

# --------------------------------------------------------------------------- shapes
# The shape of a body or an obstacle: one class per shape type, holding only the shape's
# fields; bodies and obstacles add their own fields to the same shape classes
# (mpmflow.geometry builds the geometry from them).

SHAPE_TYPES = ("box", "cylinder", "sphere", "disc", "polygon", "mesh")
_TYPE_DOC = (
    'Shape: "box" (the default; min, max), "disc" (2D; centre, radius), "polygon" '
    '(2D; vertices), "sphere" (3D; centre, radius), "cylinder" (3D; centre, axis, '
    'radius, length) or "mesh" (3D; a closed triangle surface from an STL or OBJ file: '
    "path, scale, translate). Each type takes only its own shape keys."
)


def _type_field(kind: str) -> Any:
    return Field(kind, description=_TYPE_DOC)


def _centre() -> Any:
    return Field(
        description="Centre (m) of a disc or sphere; of a cylinder, the centre of "
        "its base, where its axis starts.",
        min_length=2,
        max_length=3,
        examples=[[0.2, 0.1]],
    )


def _radius() -> Any:
    return Field(description="Radius (m) of a disc, sphere or cylinder.", gt=0, examples=[0.05])


class _BoxShape(Section):
    VECTORS: ClassVar = ("min", "max")
    type: Literal["box"] = _type_field("box")
    min: list[float] = Field(
        description="Lower corner of a box (m).", examples=[[0.0, 0.0]], min_length=2, max_length=3
    )
    max: list[float] = Field(
        description="Upper corner of a box (m).",
        examples=[[0.114, 0.228]],
        min_length=2,
        max_length=3,
    )

    @model_validator(mode="after")
    def _ordered(self) -> Self:
        flat = [k for k, (a, b) in enumerate(zip(self.min, self.max)) if not b > a]
        if flat:
            raise ValueError(
                "each entry of max must be larger than the entry of min: along "
                + " and ".join("xyz"[k] for k in flat)
                + f" max = {self.max} does not exceed min = {self.min}, so the box has no "
                "size there; give max larger than min"
            )
        return self


class _CylinderShape(Section):
    VECTORS: ClassVar = ("centre", "axis")
    type: Literal["cylinder"] = _type_field("cylinder")
    centre: list[float] = _centre()
    axis: list[float] = Field(
        description="Direction of a cylinder's axis from the centre of its base (any length; "
        "[0, 0, 1] stands it upright).",
        min_length=3,
        max_length=3,
        examples=[[0, 0, 1]],
    )
    radius: float = _radius()
    length: float = Field(
        description="Length (m) of a cylinder along its axis.", gt=0, examples=[0.2]
    )

    @model_validator(mode="after")
    def _axis(self) -> Self:
        if not any(self.axis):
            raise ValueError(
                "the cylinder's axis must not be [0, 0, 0]; give its direction, "
                "e.g. axis = [0, 0, 1]"
            )
        return self


class _SphereShape(Section):
    VECTORS: ClassVar = ("centre",)
    type: Literal["sphere"] = _type_field("sphere")
    centre: list[float] = _centre()
    radius: float = _radius()


class _DiscShape(Section):
    VECTORS: ClassVar = ("centre",)
    type: Literal["disc"] = _type_field("disc")
    centre: list[float] = _centre()
    radius: float = _radius()


class _PolygonShape(Section):
    VECTORS: ClassVar = ()
    type: Literal["polygon"] = _type_field("polygon")
    vertices: list[Annotated[list[float], Field(min_length=2, max_length=2)]] = Field(
        description="Corners of a polygon (2D) in order, [[x, y], ...] (m); the last joins the "
        "first. Any simple polygon (convex or not; its edges must not cross).",
        min_length=3,
        examples=[[[0.2, 0.0], [0.3, 0.0], [0.25, 0.05]]],
    )

    @model_validator(mode="after")
    def _simple(self) -> Self:
        message = shapes.polygon_problem(self.vertices)
        if message:
            raise ValueError(message)
        return self


class _MeshShape(Section):
    VECTORS: ClassVar = ("translate",)
    type: Literal["mesh"] = _type_field("mesh")
    path: str = Field(
        description="A mesh's file (STL or OBJ, read with trimesh): the closed surface of a "
        "solid, relative to the case file's folder. Its coordinates are taken in metres "
        "(times scale).",
        examples=["geometry/pier.stl"],
    )
    scale: float = Field(
        1.0,
        gt=0,
        description="Factor from a mesh file's units to metres "
        "(1: the file is in metres; 0.001: in millimetres).",
    )
    translate: list[float] = Field(
        [0.0, 0.0, 0.0],
        description="Shift (m) applied to a mesh after scaling.",
        min_length=3,
        max_length=3,
    )

    @field_validator("path")
    @classmethod
    def _given(cls, path: str) -> str:
        # not Field(min_length=1): pydantic's length check refuses a path that is not
        # UTF-8 (a folder named in another encoding, held in str by surrogate escapes)
        if not path:
            raise ValueError("give the path of the mesh file (STL or OBJ)")
        return path


class _BodyFields(Section):
    particles_per_cell: int = Field(
        2,
        ge=1,
        le=16,
        description="Material points per cell along each axis (4 gives 16 per "
        "cell in 2D, 64 in 3D). Points sit on a lattice aligned with the grid; a body of any "
        "shape keeps the lattice points inside it (and outside every obstacle).",
    )
    velocity: list[float] = Field(
        [0.0, 0.0],
        description="Initial velocity of the body (m/s); at rest by default, in 2D and 3D.",
        min_length=2,
        max_length=3,
    )
    around_obstacles: bool = Field(
        False,
        description="true = fill the body's shape except where obstacles are (water "
        "in a tank round a pier: the lattice points inside obstacles are not seeded). false "
        "(default) = a body that overlaps an obstacle is refused, as a likely mistake of "
        "position.",
    )
    initial_pressure: Literal["zero", "hydrostatic"] = Field(
        "zero",
        description='Initial particle pressure: "zero", or "hydrostatic" = '
        "density * |g| * depth below the body's highest point against gravity (for a box its "
        "highest corner). The "
        "explicit scheme starts from the matching compression (volume (1 - p/K) m/density), "
        "which spares it the acoustic transient of a column released without pressure; the "
        "projection scheme computes the pressure anew in its first step.",
    )
    free_water: bool = Field(
        False,
        description="true = the body is free water beside a saturated soil (material.model = "
        '"poroelastic"): particles of material.water_density with no skeleton, the '
        "reservoir above a seabed; water flows between it and the soil's pores by Darcy's "
        "law across their common faces. false: the saturated soil (or the material).",
    )


class Box(_BodyFields, _BoxShape):
    surface_amplitude: float = Field(
        0.0,
        description='Amplitude A (m) of a cosine top surface (type = "box" only), for '
        "standing-wave "
        "sloshing: particles are kept where y < max[1] + A cos(pi (x - min[0]) / (max[0] - "
        "min[0])), half a wavelength across the box (the first sloshing mode of a tank as "
        "wide as the box); the box is seeded up to max[1] + |A|. 0 = flat top. |A| must be "
        'smaller than the box\'s height. With initial_pressure = "hydrostatic" the depth is '
        "measured from this surface.",
        examples=[0.01],
    )

    @model_validator(mode="after")
    def _amplitude(self) -> Self:
        if abs(self.surface_amplitude) >= self.max[1] - self.min[1]:
            raise ValueError(
                f"|surface_amplitude| = {abs(self.surface_amplitude):g} m must be smaller than "
                f"the box's height max[1] - min[1] = {self.max[1] - self.min[1]:g} m"
            )
        return self


class CylinderBody(_BodyFields, _CylinderShape):
    pass


class SphereBody(_BodyFields, _SphereShape):
    pass


class DiscBody(_BodyFields, _DiscShape):
    pass


class PolygonBody(_BodyFields, _PolygonShape):
    pass


class MeshBody(_BodyFields, _MeshShape):
    pass


class _ObstacleFields(Section):
    name: str | None = Field(
        None,
        description="Name of the obstacle, for messages and outputs (letters, digits, "
        "_ . + -); optional.",
        pattern=r"^[A-Za-z0-9_.+-]{1,64}$",
        examples=["pier"],
    )
    walls: Literal["slip", "no_slip", "domain"] = Field(
        "domain",
        description='Wall condition on the obstacle\'s surface: "slip", '
        '"no_slip", or "domain" = the same as domain.walls (which must then be one '
        "condition for every wall).",
    )
    motion: Motion | None = Field(
        None,
        description="How the obstacle moves ([obstacles.motion]: a velocity, an oscillation "
        "or a table of its path; src/core/bodies.hpp); none: it stays where it is.",
    )


class BoxObstacle(_ObstacleFields, _BoxShape):
    pass


class CylinderObstacle(_ObstacleFields, _CylinderShape):
    pass


class SphereObstacle(_ObstacleFields, _SphereShape):
    pass


class DiscObstacle(_ObstacleFields, _DiscShape):
    pass


class PolygonObstacle(_ObstacleFields, _PolygonShape):
    pass


class MeshObstacle(_ObstacleFields, _MeshShape):
    pass


def _shape_tag(value: Any) -> str:
    """The ``type`` of a body or obstacle table ("box" when not given)."""
    kind = value.get("type", "box") if isinstance(value, dict) else getattr(value, "type", "box")
    return kind if isinstance(kind, str) else repr(kind)


# a body or an obstacle: one of the shape classes, chosen by its ``type`` (SHAPE_TYPES)
Body = Annotated[
    Annotated[Box, Tag("box")]
    | Annotated[CylinderBody, Tag("cylinder")]
    | Annotated[SphereBody, Tag("sphere")]
    | Annotated[DiscBody, Tag("disc")]
    | Annotated[PolygonBody, Tag("polygon")]
    | Annotated[MeshBody, Tag("mesh")],
    Discriminator(_shape_tag),
]
Obstacle = Annotated[
    Annotated[BoxObstacle, Tag("box")]
    | Annotated[CylinderObstacle, Tag("cylinder")]
    | Annotated[SphereObstacle, Tag("sphere")]
    | Annotated[DiscObstacle, Tag("disc")]
    | Annotated[PolygonObstacle, Tag("polygon")]
    | Annotated[MeshObstacle, Tag("mesh")],
    Discriminator(_shape_tag),
]
