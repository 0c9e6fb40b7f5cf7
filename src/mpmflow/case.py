"""Case files: a TOML document validated against the schema below (SI units throughout).

The schema is the single source of the case-file reference: every key's description here
is what the documentation and the error messages show.
"""

import difflib
import sys
import typing
from pathlib import Path
from typing import Annotated, ClassVar, Literal, Optional, Union

import numpy as np
from pydantic import (BaseModel, ConfigDict, Discriminator, Field, PrivateAttr, Tag,
                      ValidationError, ValidationInfo, model_validator)

from . import bodies as geometry
from . import materials, placement, shapes
from .errors import CaseError
from .grid import Grid
from .stability import case_stable_time_step, initial_speed, sound_speed, time_step

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

# checkpoint files are numbered by step with 9 digits (checkpoint_NNNNNNNNN.npz): the most
# steps a run can take. (At 2 ms per step, the cost of a small case, that is 23 days.)
MAX_STEPS = 999_999_999
COURANT = 1.0  # time.courant's default (docs/method.md, "Adaptive steps")
MAX_DT = 1e-2  # s: time.max_dt's default, the paper's step for its dam break
MAX_CASE_BYTES = 16 * 2**20  # a case file is a page of TOML; anything larger is not one


class _Section(BaseModel):
    model_config = ConfigDict(extra="forbid", validate_assignment=True, allow_inf_nan=False)


class Domain(_Section):
    size: list[float] = Field(
        description="Extent of the rectangular domain (m), one value per axis: 2 entries for "
        "a 2D case (x, y; y up), 3 for a 3D case (x, y, z; z up). The domain is [0, size]; "
        "its boundaries are walls. Every other vector of the case (bodies' min, max and "
        "velocity, gravity, probe positions) has as many entries.",
        examples=[[0.42, 0.44]], min_length=2, max_length=3)
    walls: Literal["slip", "no_slip"] = Field(
        "slip", description="Wall condition on all domain boundaries. Walls are contact "
        "conditions: a wall holds the material where it presses against it and lets go where "
        "holding it would need suction while it moves away, so water falls from a ceiling "
        "and leaves a wall freely. no_slip also stops tangential motion where the wall "
        "holds.")

    @model_validator(mode="after")
    def _positive(self):
        if any(s <= 0 for s in self.size):
            raise ValueError("every entry of domain.size must be positive (metres)")
        return self


class GridSettings(_Section):
    spacing: float = Field(
        description="Cell size of the background grid (m). Walls lie on grid lines: a side of "
        "the domain that is not a whole number of cells is extended to the next whole cell "
        "(reported at start and in summary.json).", gt=0, examples=[0.004])


# --------------------------------------------------------------------------- shapes
# The shape of a body or an obstacle: one class per shape type, holding only the shape's
# fields; bodies and obstacles add their own fields to the same shape classes
# (mpmflow.shapes builds the geometry from them).

SHAPE_TYPES = ("box", "cylinder", "sphere", "disc", "polygon", "mesh")
_TYPE_DOC = (
    "Shape: \"box\" (the default; min, max), \"disc\" (2D; centre, radius), \"polygon\" "
    "(2D; vertices), \"sphere\" (3D; centre, radius), \"cylinder\" (3D; centre, axis, "
    "radius, length) or \"mesh\" (3D; a closed triangle surface from an STL or OBJ file: "
    "path, scale, translate). Each type takes only its own shape keys.")


def _type_field(kind):
    return Field(kind, description=_TYPE_DOC)


def _centre():
    return Field(description="Centre (m) of a disc or sphere; of a cylinder, the centre of "
                 "its base, where its axis starts.", min_length=2, max_length=3,
                 examples=[[0.2, 0.1]])


def _radius():
    return Field(description="Radius (m) of a disc, sphere or cylinder.", gt=0,
                 examples=[0.05])


class _BoxShape(_Section):
    VECTORS: ClassVar = ("min", "max")
    type: Literal["box"] = _type_field("box")
    min: list[float] = Field(description="Lower corner of a box (m).", examples=[[0.0, 0.0]],
                             min_length=2, max_length=3)
    max: list[float] = Field(description="Upper corner of a box (m).",
                             examples=[[0.114, 0.228]], min_length=2, max_length=3)

    @model_validator(mode="after")
    def _ordered(self):
        if any(b <= a for a, b in zip(self.min, self.max)):
            raise ValueError("each entry of max must be larger than the entry of min")
        return self


class _CylinderShape(_Section):
    VECTORS: ClassVar = ("centre", "axis")
    type: Literal["cylinder"] = _type_field("cylinder")
    centre: list[float] = _centre()
    axis: list[float] = Field(
        description="Direction of a cylinder's axis from the centre of its base (any length; "
        "[0, 0, 1] stands it upright).", min_length=3, max_length=3, examples=[[0, 0, 1]])
    radius: float = _radius()
    length: float = Field(description="Length (m) of a cylinder along its axis.", gt=0,
                          examples=[0.2])

    @model_validator(mode="after")
    def _axis(self):
        if not any(self.axis):
            raise ValueError("the cylinder's axis must not be [0, 0, 0]; give its direction, "
                             "e.g. axis = [0, 0, 1]")
        return self


class _SphereShape(_Section):
    VECTORS: ClassVar = ("centre",)
    type: Literal["sphere"] = _type_field("sphere")
    centre: list[float] = _centre()
    radius: float = _radius()


class _DiscShape(_Section):
    VECTORS: ClassVar = ("centre",)
    type: Literal["disc"] = _type_field("disc")
    centre: list[float] = _centre()
    radius: float = _radius()


class _PolygonShape(_Section):
    VECTORS: ClassVar = ()
    type: Literal["polygon"] = _type_field("polygon")
    vertices: list[Annotated[list[float], Field(min_length=2, max_length=2)]] = Field(
        description="Corners of a polygon (2D) in order, [[x, y], ...] (m); the last joins the "
        "first. Any simple polygon (convex or not; its edges must not cross).", min_length=3,
        examples=[[[0.2, 0.0], [0.3, 0.0], [0.25, 0.05]]])

    @model_validator(mode="after")
    def _simple(self):
        message = shapes.polygon_problem(self.vertices)
        if message:
            raise ValueError(message)
        return self


class _MeshShape(_Section):
    VECTORS: ClassVar = ("translate",)
    type: Literal["mesh"] = _type_field("mesh")
    path: str = Field(
        description="A mesh's file (STL or OBJ, read with trimesh): the closed surface of a "
        "solid, relative to the case file's folder. Its coordinates are taken in metres "
        "(times scale).", min_length=1, examples=["geometry/pier.stl"])
    scale: float = Field(1.0, gt=0, description="Factor from a mesh file's units to metres "
                         "(1: the file is in metres; 0.001: in millimetres).")
    translate: list[float] = Field([0.0, 0.0, 0.0], description="Shift (m) applied to a mesh "
                                   "after scaling.", min_length=3, max_length=3)


class _BodyFields(_Section):
    particles_per_cell: int = Field(
        2, ge=1, le=16, description="Material points per cell along each axis (4 gives 16 per "
        "cell in 2D, 64 in 3D). Points sit on a lattice aligned with the grid; a body of any "
        "shape keeps the lattice points inside it (and outside every obstacle).")
    velocity: list[float] = Field([0.0, 0.0], description="Initial velocity of the body (m/s); "
                                  "at rest by default, in 2D and 3D.",
                                  min_length=2, max_length=3)
    around_obstacles: bool = Field(
        False, description="true = fill the body's shape except where obstacles are (water "
        "in a tank round a pier: the lattice points inside obstacles are not seeded). false "
        "(default) = a body that overlaps an obstacle is refused, as a likely mistake of "
        "position.")
    initial_pressure: Literal["zero", "hydrostatic"] = Field(
        "zero", description="Initial particle pressure: \"zero\", or \"hydrostatic\" = "
        "density * |g| * depth below the body's highest point against gravity (for a box its "
        "highest corner). The "
        "explicit scheme starts from the matching compression (volume (1 - p/K) m/density), "
        "which spares it the acoustic transient of a column released without pressure; the "
        "projection scheme computes the pressure anew in its first step.")


class Box(_BodyFields, _BoxShape):
    surface_amplitude: float = Field(
        0.0, description="Amplitude A (m) of a cosine top surface (type = \"box\" only), for "
        "standing-wave "
        "sloshing: particles are kept where y < max[1] + A cos(pi (x - min[0]) / (max[0] - "
        "min[0])), half a wavelength across the box (the first sloshing mode of a tank as "
        "wide as the box); the box is seeded up to max[1] + |A|. 0 = flat top. |A| must be "
        "smaller than the box's height. With initial_pressure = \"hydrostatic\" the depth is "
        "measured from this surface.", examples=[0.01])

    @model_validator(mode="after")
    def _amplitude(self):
        if abs(self.surface_amplitude) >= self.max[1] - self.min[1]:
            raise ValueError(
                f"|surface_amplitude| = {abs(self.surface_amplitude):g} m must be smaller than "
                f"the box's height max[1] - min[1] = {self.max[1] - self.min[1]:g} m")
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


class _ObstacleFields(_Section):
    name: Optional[str] = Field(
        None, description="Name of the obstacle, for messages and outputs (letters, digits, "
        "_ . + -); optional.", pattern=r"^[A-Za-z0-9_.+-]{1,64}$", examples=["pier"])
    walls: Literal["slip", "no_slip", "domain"] = Field(
        "domain", description="Wall condition on the obstacle's surface: \"slip\", "
        "\"no_slip\", or \"domain\" = the same as domain.walls.")


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


def _shape_tag(value):
    """The ``type`` of a body or obstacle table ("box" when not given)."""
    kind = value.get("type", "box") if isinstance(value, dict) else getattr(value, "type", "box")
    return kind if isinstance(kind, str) else repr(kind)


def _shape_union(*models):
    return Annotated[Union[tuple(Annotated[m, Tag(t)] for m, t in zip(models, SHAPE_TYPES))],
                     Discriminator(_shape_tag)]


Body = _shape_union(Box, CylinderBody, SphereBody, DiscBody, PolygonBody, MeshBody)
Obstacle = _shape_union(BoxObstacle, CylinderObstacle, SphereObstacle, DiscObstacle,
                        PolygonObstacle, MeshObstacle)


class Material(_Section):
    model: Literal[tuple(materials.MATERIALS)] = Field(
        "water", description="Constitutive model: \"water\" (inviscid, the default), "
        "\"newtonian\" (viscosity), \"herschel_bulkley\" (yield-stress material; Bingham "
        "with flow_index = 1: consistency, yield_stress, flow_index, max_viscosity) or "
        "\"mu_i\" (dense granular flow: friction_static, friction_limit, "
        "inertial_number_ref, grain_diameter, grain_density, max_viscosity). Each takes only "
        "its own parameters; the viscous stress is solved implicitly (docs/method.md, "
        "\"Viscous materials\").")
    density: float = Field(1000.0, gt=0, description="Density (kg/m^3); with model = "
                           "\"mu_i\" the bulk density, solid fraction x grain_density.")
    viscosity: float = Field(0.0, ge=0, description="Dynamic viscosity (Pa s) of model = "
                             "\"newtonian\" (water at 20 C: 1.0e-3); 0 for \"water\".")
    consistency: float = Field(1.0, description="Consistency K (Pa s^n) of model = "
                               "\"herschel_bulkley\": |tau| = yield_stress + K rate^n "
                               "where the material flows (the plastic viscosity when n = 1).")
    yield_stress: float = Field(0.0, description="Yield stress (Pa) of model = "
                                "\"herschel_bulkley\".")
    flow_index: float = Field(1.0, description="Flow index n of model = \"herschel_bulkley\" "
                              "(1: Bingham; < 1 shear-thinning).")
    max_viscosity: float = Field(
        1e5, description="Cap of the effective viscosity (Pa s) of models "
        "\"herschel_bulkley\" and \"mu_i\" (bi-viscous regularisation): below the yield "
        "the material creeps at rate |tau| / max_viscosity instead of standing still. Larger "
        "is stiffer and costs more iterations of the viscous solve.")
    friction_static: float = Field(0.38, description="mu_s of model = \"mu_i\": the "
                                   "friction coefficient at rest (tan of the angle below which "
                                   "a layer stops; glass beads: 0.38).")
    friction_limit: float = Field(0.64, description="mu_2 of model = \"mu_i\": the friction "
                                  "coefficient at large inertial number (glass beads: 0.64).")
    inertial_number_ref: float = Field(0.279, description="I0 of model = \"mu_i\" (glass "
                                       "beads: 0.279).")
    grain_diameter: float = Field(0.53e-3, description="Grain diameter d (m) of model = "
                                  "\"mu_i\" (glass beads: 0.53e-3).")
    grain_density: float = Field(2450.0, description="Density of the grains (kg/m^3) of "
                                 "model = \"mu_i\"; the solid fraction is density / "
                                 "grain_density (glass beads: 2450).")
    bulk_modulus: float = Field(
        2.2e9, gt=0, description="Bulk modulus K (Pa) of the weakly compressible material of "
        "the explicit scheme, p = -K * volumetric strain (water: 2.2e9). It sets the sound "
        "speed sqrt(K / density) and with it the stable time step. Not used by the projection "
        "scheme, whose material is incompressible.")

    @model_validator(mode="after")
    def _model_parameters(self):
        materials.check(self)
        return self


class Physics(_Section):
    gravity: list[float] = Field([0.0, -9.81], description="Gravitational acceleration (m/s^2); "
                                 "the default points down the last axis, [0, 0, -9.81] in 3D.",
                                 min_length=2, max_length=3)


class Time(_Section):
    dt: Union[Literal["auto"], float] = Field(
        description="Time step (s), or \"auto\". With \"auto\" the projection scheme sets "
        "every step from the particles' speeds: dt = time.courant grid.spacing / max |v_p|, "
        "at most time.max_dt, the last steps before an output time shortened to land on it; "
        "the explicit scheme takes its stable step h / (c + |v|) (sound speed "
        "c = sqrt(K / density)) times time.safety_factor.", examples=[1e-3])
    safety_factor: float = Field(
        0.5, gt=0, le=1, description="Fraction of the stable explicit time step used by "
        "time.dt = \"auto\" (dimensionless).")
    courant: float = Field(
        COURANT, gt=0, le=10, description="Courant number of the projection scheme's steps "
        "with time.dt = \"auto\": the fastest particle crosses this many cells per step "
        "(dimensionless; measured against the dam break's validation rows, docs/method.md).")
    max_dt: float = Field(
        MAX_DT, gt=0, description="Longest step of the projection scheme with time.dt = "
        "\"auto\" (s): the step of a flow at rest, and the cap when it moves slowly.")
    end: float = Field(description="Simulated time at which the run stops (s).", gt=0,
                       examples=[1.0])

    @model_validator(mode="after")
    def _positive(self):
        if self.dt != "auto" and self.dt <= 0:
            raise ValueError("time.dt must be greater than 0 (seconds), or \"auto\"")
        return self


class Output(_Section):
    interval: float = Field(
        0.01, gt=0, description="Simulated time between rows of timeseries.csv (s). The steps "
        "between two output times are all equal and at most time.dt, so every output time is "
        "landed on exactly.")
    snapshot_interval: Optional[float] = Field(
        None, gt=0, description="Simulated time between particle snapshots (s); defaults to "
        "output.interval. Snapshots are written at the first output time at or after each "
        "multiple (so an interval shorter than output.interval means every output).")
    snapshots: bool = Field(True, description="Write particle snapshots (VTU files and a "
                            "particles.pvd time series for ParaView).")


class Checkpoint(_Section):
    interval: float = Field(
        0.1, gt=0, description="Simulated time between checkpoints (s), written at the first "
        "output time at or after each multiple (every output for an interval shorter than "
        "output.interval), at the end of the run and when it is interrupted (Ctrl-C, "
        "SIGTERM). A checkpoint (checkpoint_NNNNNNNNN.npz in the output "
        "folder, the latest two kept) holds everything needed to continue: `mpmflow run CASE "
        "--out DIR --restart` resumes from the latest and reproduces the uninterrupted run "
        "bit for bit.")


class ProbeData(_Section):
    path: str = Field(
        description="The measured series' CSV file (a header line naming the columns, then "
        "rows of numbers separated by commas), relative to the case file's folder (to the "
        "working folder for a case built in Python). Checked when the case is loaded.",
        examples=["../shared/data/validation/spheric_test2_kleefsman2005_marin_exp_P1-P8_H1-H4.csv"])
    column: str = Field(
        description="The header of the file's column that holds the measured values, in the "
        "probe's unit (Pa for pressure, m for level).", examples=["P1 [Pa]"])
    time_column: str = Field(
        "time [s]", description="The header of the file's column of times (s).")


class Probe(_Section):
    name: str = Field(
        description="Name of the probe: its column in probes.csv (letters, digits, _ . + -).",
        pattern=r"^[A-Za-z0-9_.+-]{1,64}$", examples=["sensor_1"])
    quantity: Literal["pressure", "level"] = Field(
        description="What the probe measures at every output time, into probes.csv: "
        "\"pressure\" = the water's pressure (Pa) at position, from the particles in a "
        "window (a square, in 3D a cube, of side probes.N.window) around it: centred on "
        "position, except that along an axis where position lies on a wall the window lies "
        "on the water's side (one window in from the wall), and cut at any other wall; read "
        "as probes.N.estimate says; 0 when no particle is in the window (a dry sensor reads "
        "the atmosphere's gauge pressure). \"level\" = a water-level gauge on the vertical "
        "line through position (x in 2D; x and y in 3D): the level (m) above the gauge's foot "
        "position, read from the cell volume fraction interpolated linearly (bilinearly in "
        "3D) between the cell columns around the line, as probes.N.gauge says.",
        examples=["pressure"])
    position: list[float] = Field(
        description="Where the probe is (m): the sensor's point for \"pressure\", the foot of "
        "the gauge for \"level\" (e.g. [x, 0] on the floor in 2D, [x, y, 0] in 3D). Inside "
        "the domain.",
        min_length=2, max_length=3, examples=[[0.42, 0.01]])
    window: Optional[float] = Field(
        None, gt=0, description="Side of a pressure probe's window (m); none = the fewest "
        "whole grid cells that hold the 2 (D + 1) particles of a fit at the sparsest body's "
        "particles_per_cell (one cell at 3 or more per axis in 2D, 2 or more in 3D; two "
        "cells at the default 2 in 2D). A larger window averages more particles (less "
        "noise, less resolution).")
    estimate: Literal["fit", "mean"] = Field(
        "fit", description="How a pressure probe reads its window's particles: \"fit\" = "
        "the value at position of the plane p = a + b.(x - position) fitted to them by least "
        "squares, the pressure AT the point (exact on a hydrostatic column, also for a sensor "
        "on a wall, whose window lies beside it; falls back to the mean with too few "
        "particles or particles in one layer, and reads 0 for a negative value among "
        "pressures that are not, each counted in summary.json's caps_and_fallbacks); \"mean\" = their mean pressure, the pressure at their "
        "centre (half a window from a wall sensor: rho g window/2 low on the column at "
        "rest).")
    gauge: Literal["integral", "first_drop"] = Field(
        "integral", description="How a level probe reads the volume fraction f on its line: "
        "\"integral\" = the integral of f from the foot up (m), the water's depth gathered "
        "into one layer, as a resistance or capacitance wave probe reads its wetted wire "
        "(and OpenFOAM's interfaceHeight): a splash or spray above the layer counts by its "
        "volume, an air pocket under the surface counts out by its volume, an aerated cell "
        "at the foot lowers it by its air only; \"first_drop\" = the height above the foot "
        "where f first drops below 1/2 going up (the top of the first layer: 0 when the "
        "foot's cell is less than half full, splashes above the layer not counted). Level "
        "probes only.")
    data: Optional[ProbeData] = Field(
        None, description="The measured series to compare with ([probes.data] table: path, "
        "column, time_column): `mpmflow plot` draws it beside the probe's.")


class Execution(_Section):
    threads: Union[Literal["auto"], int] = Field(
        "auto", description="Threads of the compiled kernels: \"auto\" uses the cores that "
        "other programs leave idle, measured when the run starts and again about every "
        "second at output times (a run beside another busy program drops to fewer threads "
        "instead of waiting for a shared core), or a number, fixed for the whole run. The "
        "environment variable MPMFLOW_THREADS, when set, takes the place of \"auto\". "
        "Results do not depend on the number of threads. May change on --restart.")

    @model_validator(mode="after")
    def _positive(self):
        if self.threads != "auto" and self.threads < 1:
            raise ValueError("execution.threads must be \"auto\" or at least 1")
        return self


# The formulation presets: defaults of the settings that separate mpmflow's projection from
# the plain reading of the paper (measured against each other in docs/variants.md and, for the
# volume correction and the sparse threshold, in docs/method.md).
FORMULATIONS = {
    "mpmflow": {"free_surface": "subcell", "wall_flux": True, "partial_cell_quadrature": "gauss",
                "surface_quadrature": "divergence", "sparse_cell_threshold": 0.01,
                "volume_correction": 0.5,
                "density_correction": 0.0, "flip": 0.99},
    "paper": {"free_surface": "node", "wall_flux": False, "partial_cell_quadrature": "particles",
              "surface_quadrature": "gauss", "sparse_cell_threshold": 0.2,
              "volume_correction": 0.0,
              "density_correction": 0.0, "flip": 1.0},
}


class Solver(_Section):
    scheme: Literal["projection", "explicit"] = Field(
        "projection", description="Time integration scheme: \"projection\" is the implicit "
        "Chorin projection of Kularathna & Soga (2017); \"explicit\" is the explicit weakly "
        "compressible MPM the paper compares with (update stress last, p = -K * volumetric "
        "strain once per cell; material.bulk_modulus; time step limited by the sound speed).")
    formulation: Literal["mpmflow", "paper"] = Field(
        "mpmflow", description="Preset for free_surface, wall_flux, partial_cell_quadrature, "
        "surface_quadrature, sparse_cell_threshold, volume_correction, density_correction and "
        "flip: \"paper\" is "
        "the plain reading of Kularathna & Soga (2017) (p = 0 at free-surface nodes, "
        "homogeneous Neumann walls, material-point quadrature in partial cells, cells below "
        "theta = 0.2 left out, no correction of the particles' volume, pure FLIP); "
        "\"mpmflow\" is the default, which keeps a column at rest exactly at rest and the "
        "material at its volume. Keys set explicitly override the preset.")
    flip: float = Field(None, ge=0, le=1, description="FLIP fraction of the particle velocity "
                        "update per millisecond of simulated time: a step of dt blends FLIP and "
                        "PIC with the fraction flip^(dt / 1 ms), so the PIC damping per second "
                        "is the same whatever the time step and the scheme. 1 = pure FLIP "
                        "(the paper), 0 = pure PIC. The default keeps 1% PIC per millisecond, "
                        "which stops the thin surge tip from running ahead on FLIP noise.")
    full_cell_threshold: float = Field(
        0.9, gt=0, le=1, description="Cells with volume fraction theta at or above this are full "
        "and integrated with 2x2 Gauss points (paper: 0.9).")
    sparse_cell_threshold: float = Field(
        None, gt=0, lt=1, description="Cells with theta below this are left out of the "
        "pressure system (paper: 0.2). With free_surface = \"subcell\" the surface is placed "
        "by the nodal volume fraction, not by this threshold, and a low threshold keeps the "
        "few particles above a surface that lies on a grid line inside the system (left out, "
        "they fall freely until they rejoin it, which stirs the surface).")
    partial_cell_quadrature: Literal["gauss", "particles"] = Field(
        None, description="Quadrature of partial cells (sparse <= theta < full): "
        "\"particles\" integrates with the material points (the paper); \"gauss\" with Gauss "
        "points over the whole cell, consistent with free_surface = \"subcell\".")
    surface_quadrature: Literal["divergence", "consistent", "gauss"] = Field(
        None, description="With partial_cell_quadrature = \"gauss\": how the cells the free "
        "surface passes through are integrated besides the Laplacian (Gauss points). "
        "\"divergence\": the divergence of the predicted velocity (eq. 15) over the cell's "
        "material points, because the grid velocity in the air part of the cell is an "
        "extrapolation no equation constrains and its divergence, over the whole cell, does "
        "work against the extrapolated pressure (a standing wave gained energy); "
        "\"consistent\": the corrector's gradient and volumes too, so that the projection "
        "only takes energy out (at 0.01 m a standing wave then loses 1.8% per period and "
        "the coarse surge front is 0.007 a slower); \"gauss\": Gauss points over the whole "
        "cell for all (the earlier default). See docs/method.md, \"Energy\".")
    free_surface: Literal["subcell", "node"] = Field(
        None, description="Free-surface condition: \"node\" sets p = 0 at nodes bordering "
        "left-out cells (the paper); \"subcell\" places p = 0 at the f = 1/2 level of the nodal "
        "volume fraction with ghost-fluid extrapolation.")
    wall_flux: bool = Field(
        None, description="Use the wall term of the weak form (grad p . n = rho/dt v*.n on "
        "wetted walls) with the divergence of the unconstrained v*. false = the paper's "
        "homogeneous Neumann condition with the wall-constrained v*.")
    ghost_theta_min: float = Field(
        0.01, gt=0, le=1, description="Smallest fractional distance from an unknown node to the "
        "free surface used in the ghost extrapolation (subcell only); keeps the system well "
        "conditioned when the surface passes very close to a node.")
    volume_correction: float = Field(
        None, ge=0, le=1, description="Volume correction rate beta (dimensionless, per step): "
        "the particles' volume fraction on the cell grid is brought back towards 1 by moving "
        "the particles (never their velocity) along -grad q, -lap q = volume fraction - 1 on "
        "the cells holding material (q = 0 in empty cells, no flux through walls; within one "
        "cell of the free surface only an excess counts). It closes gaps and undoes packing, "
        "removing the fraction beta of the volume error each step. 0 = off (the paper).")
    volume_correction_interval: float = Field(
        2e-3, gt=0, description="Simulated time between volume corrections (s): the "
        "correction runs every round(interval / time.dt) steps, every step when time.dt is "
        "this long or longer, removing the fraction volume_correction of the volume error "
        "each time. A correction costs about a fifth of a step; at time.dt = 1 ms, every "
        "second step halves that with the same volume, dam-break accuracy and sloshing "
        "energy (docs/method.md).")
    density_correction: float = Field(
        None, ge=0, le=1, description="The earlier, velocity-based density correction beta "
        "(dimensionless): where the particles give a node more material volume than the node "
        "holds (vol_i > V_i), the projection asks for div v = beta (vol_i/V_i - 1)/dt. It only "
        "spreads packed particles and, under FLIP, adds kinetic energy (the water loosens and "
        "a standing wave grows): kept for comparison, off by default; use "
        "solver.volume_correction instead.")
    linear_solver: Literal["multigrid", "amg", "direct"] = Field(
        "multigrid", description="Pressure solver: \"multigrid\" = conjugate gradients "
        "preconditioned by geometric multigrid on the grid (compiled); \"amg\" = conjugate "
        "gradients with smoothed-aggregation algebraic multigrid (pyamg); \"direct\" = sparse "
        "LU (SciPy).")
    tolerance: float = Field(1e-8, gt=0, lt=1, description="Relative residual the pressure "
                             "solve must reach every step; the run stops if it does not.")
    max_iterations: int = Field(200, ge=1, le=100000,
                                description="Iteration limit of the pressure solve.")
    max_speed: float = Field(
        100.0, gt=0, description="Largest particle speed (m/s) the run accepts: a faster "
        "particle means the computation is blowing up, and the run stops with the step, time "
        "and particle (exit code 3), keeping the outputs written so far. Checked after every "
        "output interval (the explicit scheme: every step). The default, 100 m/s, is about "
        "ten times the speed of water falling 5 m; raise it for faster flows.")
    pressure_smoothing: Literal["nodal", "none"] = Field(
        "nodal", description="Explicit scheme: the pressure is evaluated once per cell from "
        "the volumetric strain of the particles in it, and that cell pressure drives the "
        "motion. The particles report it smoothed with \"nodal\" (each node takes the "
        "volume-weighted average of the cells around it, interpolated to the particle) or "
        "as their cell's value with \"none\".")

    explicit_mass_cutoff: float = Field(
        0.0, ge=0, lt=1, description="Explicit scheme: a node whose mass is below this "
        "fraction of a full node's (density * grid.spacing^2 per unit depth) takes gravity "
        "only, no internal force, so that nearly empty nodes do not receive huge "
        "accelerations (0 = every node with mass).")
    explicit_bulk_viscosity: list[float] = Field(
        [0.06, 1.5], min_length=2, max_length=2, description="Explicit scheme: artificial "
        "bulk viscosity [linear, quadratic] (dimensionless), as in explicit hydrocodes: a "
        "compressing cell (div v = D < 0) adds q = rho (linear c h |D| + quadratic h^2 D^2) to "
        "its pressure (c the sound speed, h the grid spacing); with time.dt = \"auto\" the "
        "step is then at most h / (|v| + Q + sqrt(Q^2 + c^2)), Q = linear c + quadratic h |D| "
        "of the most compressing cell. The default, the hydrocodes' usual [0.06, 1.5], carries "
        "the K = 2.2 GPa dam break at 0.004 m through the wall impact, where without it a "
        "particle of the jet up the wall reached 124 m/s at 0.248 s; [0, 0] = none.")
    explicit_cell_threshold: float = Field(
        0.1, ge=0, lt=1, description="Explicit scheme: a cell whose particles' reference "
        "volume fills less than this fraction of it is too empty to define a volumetric "
        "strain: it holds no pressure and its particles keep their reference volume "
        "(0 = every cell with a particle). The default, 0.1, leaves out a cell holding a "
        "single particle of the usual 16 (1/16 of the cell): without it, at K = 2.2 GPa, "
        "splashes of lone particles reached 100-500 m/s and stopped the dam break at 0.31 s.")
    explicit_tension: float = Field(
        0.0, ge=0, description="Explicit scheme: the largest tension (Pa) the material holds, "
        "p >= -explicit_tension (0 = none: free water holds no tension).")

    _from_preset: set = PrivateAttr(default_factory=set)  # keys the preset gave

    @model_validator(mode="wrap")
    @classmethod
    def _preset(cls, data, handler):
        given = None
        if isinstance(data, dict):  # not on assignment (then data is the model)
            given = set(data)
            name = data.get("formulation", "mpmflow")
            preset = FORMULATIONS.get(name) if isinstance(name, str) else None
            if preset is not None:
                data = {**preset, **data}
        model = handler(data)
        if given is not None:
            model._from_preset = set(FORMULATIONS["mpmflow"]) - given
        return model

    def __setattr__(self, name, value):
        """Assigning formulation after loading applies its preset to the keys the preset
        gave (not those set explicitly), as --set solver.formulation=... does."""
        super().__setattr__(name, value)
        if name == "formulation":
            for key in sorted(self._from_preset):
                super().__setattr__(key, FORMULATIONS[value][key])
        elif name in FORMULATIONS["mpmflow"]:
            self._from_preset.discard(name)

    @model_validator(mode="after")
    def _thresholds(self):
        if self.sparse_cell_threshold >= self.full_cell_threshold:
            raise ValueError("solver.sparse_cell_threshold must be smaller than "
                             "solver.full_cell_threshold")
        return self


class Case(_Section):
    title: str = Field("", description="Free text shown in outputs.")
    domain: Domain
    grid: GridSettings
    bodies: list[Body] = Field(
        description="Bodies of material ([[bodies]] tables), each of a shape (bodies.N.type).",
        min_length=1)
    obstacles: list[Obstacle] = Field(
        [], description="Fixed rigid obstacles ([[obstacles]] tables): structures the "
        "material flows round, of the same shapes and shape keys as bodies (obstacles.N.type; "
        "at least two grid cells thick). Bodies may surround them: the lattice points inside "
        "an obstacle are not seeded.")
    material: Material = Material()
    physics: Physics = Physics()
    time: Time
    output: Output = Output()
    solver: Solver = Solver()
    checkpoint: Checkpoint = Checkpoint()
    probes: list[Probe] = Field(
        [], description="Probes ([[probes]] tables): pressure sensors and water-level gauges "
        "sampled at every output time into probes.csv (a column per probe, named by "
        "probes.N.name; time in s).")
    execution: Execution = Execution()

    _base_dir: Optional[Path] = PrivateAttr(None)  # the case file's folder
    _shapes: dict = PrivateAttr(default_factory=dict)  # built shapes, by their tables
    _counts: dict = PrivateAttr(default_factory=dict)  # particle counts, by the geometry

    def __eq__(self, other):
        """Equal cases: the same settings and folder (the caches of shapes and counts
        aside)."""
        if not isinstance(other, Case):
            return NotImplemented
        return self.__dict__ == other.__dict__ and self._base_dir == other._base_dir

    @property
    def base_dir(self):
        """The folder relative paths of the case (mesh files) start from: the case file's,
        or the current folder for a case not read from a file."""
        return self._base_dir if self._base_dir is not None else Path.cwd()

    def _shape(self, kind, k):
        spec = getattr(self, kind)[k]
        key = (kind, k, spec.model_dump_json(), str(self.base_dir))
        if key not in self._shapes:
            self._shapes[key] = shapes.from_spec(spec, len(self.domain.size), self.base_dir,
                                                 key=f"{kind}.{k}")
        return self._shapes[key]

    def body_shape(self, k):
        """The ``mpmflow.shapes`` shape of bodies.k."""
        return self._shape("bodies", k)

    def obstacle_shape(self, k):
        """The ``mpmflow.shapes`` shape of obstacles.k."""
        return self._shape("obstacles", k)

    def particle_counts(self):
        """The exact number of particles each body is seeded with (obstacles left out)."""
        key = (self.model_dump_json(include={"bodies", "obstacles", "grid", "domain"}),
               str(self.base_dir))
        if key not in self._counts:
            obstacles = [self.obstacle_shape(j) for j in range(len(self.obstacles))]
            self._counts[key] = [
                geometry.particle_count(b, self.grid.spacing, self.body_shape(k), obstacles)
                for k, b in enumerate(self.bodies)]
        return self._counts[key]

    def _same_dimension(self):
        """Every vector has one entry per axis of domain.size; the defaults (gravity down
        the last axis, bodies at rest) follow the dimension."""
        D = len(self.domain.size)
        if "gravity" not in self.physics.model_fields_set and len(self.physics.gravity) != D:
            object.__setattr__(self.physics, "gravity", [0.0] * (D - 1) + [-9.81])
        for body in self.bodies:
            if "velocity" not in body.model_fields_set and len(body.velocity) != D:
                object.__setattr__(body, "velocity", [0.0] * D)
        vectors = [("physics.gravity", self.physics.gravity)]
        for kind, specs in (("bodies", self.bodies), ("obstacles", self.obstacles)):
            for k, spec in enumerate(specs):
                if D not in shapes.DIM_OF[spec.type]:
                    other = [t for t, d in shapes.DIM_OF.items() if D in d]
                    raise ValueError(
                        f"{kind}.{k}.type = {spec.type!r} is a shape of "
                        f"{shapes.DIM_OF[spec.type][0]}D cases, but domain.size = "
                        f"{self.domain.size} makes this case {D}D; give {kind}.{k} one of the "
                        f"{D}D shapes ({', '.join(repr(t) for t in other)})")
                vectors += [(f"{kind}.{k}.{name}", getattr(spec, name)) for name in spec.VECTORS
                            if name != "translate" and name != "axis"]
        for k, body in enumerate(self.bodies):
            vectors.append((f"bodies.{k}.velocity", body.velocity))
        vectors += [(f"probes.{k}.position", p.position) for k, p in enumerate(self.probes)]
        for name, value in vectors:
            if len(value) != D:
                raise ValueError(
                    f"{name} = {value} has {len(value)} entries but domain.size = "
                    f"{self.domain.size} has {D}: a {D}D case needs {D} entries in every "
                    f"vector; give {name} {D} entries, or domain.size {len(value)}")
        if D == 3:
            for k, body in enumerate(self.bodies):
                if getattr(body, "surface_amplitude", 0.0):
                    raise ValueError(
                        f"bodies.{k}.surface_amplitude = {body.surface_amplitude:g} m: the "
                        "cosine top surface is defined for 2D cases only so far; use a flat "
                        "box in 3D (surface_amplitude = 0)")

    @model_validator(mode="after")
    def _consistent(self, info: ValidationInfo):
        if info.context and info.context.get("base_dir") is not None:
            self._base_dir = Path(info.context["base_dir"])
        size = self.domain.size
        self._same_dimension()
        if self.obstacles and self.solver.scheme != "projection":
            raise ValueError(
                f"solver.scheme = {self.solver.scheme!r} does not take obstacles so far; run "
                "cases with [[obstacles]] with solver.scheme = \"projection\", or remove the "
                "obstacles")
        if self.material.model != "water" and self.solver.scheme != "projection":
            raise ValueError(
                f"solver.scheme = {self.solver.scheme!r} takes inviscid water only; run "
                f"material.model = {self.material.model!r} with solver.scheme = "
                "\"projection\" (which solves the viscous stress implicitly), or set "
                "material.model = \"water\"")
        folder = (info.context or {}).get("folder") if info is not None else None
        for k, probe in enumerate(self.probes):
            if probe.data is not None:
                _check_probe_data(k, probe, folder)
        if any(s < 2 * self.grid.spacing * (1 - 1e-9) for s in size):
            raise ValueError(
                f"grid.spacing = {self.grid.spacing:g} m is larger than half the domain "
                f"({size} m); the grid needs at least two cells per side")
        most = max(s / self.grid.spacing for s in size)
        if not np.isfinite(most):  # a huge finite count is the memory check's to refuse
            raise ValueError(
                f"grid.spacing = {self.grid.spacing:g} m makes {most:.3g} cells along a side "
                f"of the domain ({size} m), beyond what any computer holds; give a larger "
                "grid.spacing (the paper's dam break uses 0.004 m)")
        D = len(size)
        for k, body in enumerate(self.bodies):
            volume = (self.grid.spacing / body.particles_per_cell) ** D
            mass = self.material.density * volume
            # (a particle volume that underflows is the spacing's: the memory check's)
            if volume >= np.finfo(float).tiny and not mass >= np.finfo(float).tiny:
                raise ValueError(
                    f"material.density = {self.material.density:g} kg/m^3 gives the particles "
                    f"of bodies.{k} a mass of {mass:g} kg, too small for a floating-point "
                    "number to hold (masses and energies would be zero); give the density "
                    "in kg/m^3 (water: 1000)")
        for k, body in enumerate(self.bodies):
            if not geometry.is_box(body):
                continue  # placement.check
            crest = body.max[1] + abs(body.surface_amplitude)
            if body.surface_amplitude and crest > size[1] * (1 + 1e-12):
                raise ValueError(
                    f"bodies.{k}: the cosine surface reaches max[1] + |surface_amplitude| = "
                    f"{crest:g} m, above the domain's top at {size[1]:g} m; lower "
                    f"bodies.{k}.max or surface_amplitude, or enlarge domain.size")
            for lo, hi, s in zip(body.min, body.max, size):
                if lo < -1e-12 or hi > s * (1 + 1e-12):
                    box = " x ".join(f"[0, {s:g}]" for s in size)
                    raise ValueError(
                        f"bodies.{k} spans {body.min} to {body.max} m, outside the domain "
                        f"{box} m; move it inside (bodies.{k}.min/max) or enlarge domain.size")
        overlap = geometry.overlap_message(self.bodies, self.grid.spacing)
        if overlap:
            raise ValueError(overlap)
        body_shapes = [self.body_shape(k) for k in range(len(self.bodies))]
        obstacle_shapes = [self.obstacle_shape(k) for k in range(len(self.obstacles))]
        placement.check(self, body_shapes, obstacle_shapes)
        if obstacle_shapes:
            for k, count in enumerate(self.particle_counts()):
                message = (placement.empty_body_message(self, k, body_shapes[k],
                                                        obstacle_shapes)
                           if count == 0 else None)
                if message:
                    raise ValueError(message)
                if not self.bodies[k].around_obstacles:
                    message = placement.overlap_message(self, k, count, body_shapes[k],
                                                        obstacle_shapes)
                    if message:
                        raise ValueError(message)
        if self.solver.scheme == "projection":
            grid = Grid.covering(size, self.grid.spacing)
            if geometry.fills_grid(self.bodies, self.grid.spacing, grid.size):
                used = " x ".join(f"{s:.6g}" for s in grid.size)
                raise ValueError(
                    f"the bodies fill the whole domain ({used} m on the grid), leaving no "
                    "free surface: the projection scheme's incompressible material then has "
                    "no pressure level (the pressure system is singular). Leave empty space "
                    "above the material, at least one grid cell: lower the top of the bodies "
                    "(bodies.N.max) or enlarge domain.size")
        names = set()
        for k, probe in enumerate(self.probes):
            if probe.name in names:
                raise ValueError(f"probes.{k}.name = {probe.name!r} is the name of an earlier "
                                 "probe; give each probe its own name (its column in "
                                 "probes.csv)")
            names.add(probe.name)
            if any(not 0 <= p <= s * (1 + 1e-12) for p, s in zip(probe.position, size)):
                box = " x ".join(f"[0, {s:g}]" for s in size)
                raise ValueError(f"probes.{k}.position = {probe.position} m lies outside the "
                                 f"domain {box} m; move it inside")
            if probe.window is not None and probe.window > max(size):
                raise ValueError(f"probes.{k}.window = {probe.window:g} m is wider than the "
                                 f"domain (largest side {max(size):g} m), so it would read "
                                 "particles anywhere; give a window of a few grid cells "
                                 f"(grid.spacing = {self.grid.spacing:g} m), or none for "
                                 "the default")
        for k, body in enumerate(self.bodies):
            speed = float(np.linalg.norm(body.velocity))
            if not speed <= self.solver.max_speed:
                raise ValueError(
                    f"bodies.{k}.velocity = {body.velocity} m/s is {speed:.4g} m/s fast, above "
                    f"solver.max_speed = {self.solver.max_speed:g} m/s, at which the run would "
                    f"stop at once; give a slower velocity or raise solver.max_speed")
        if (self.time.dt == "auto" and self.solver.scheme == "projection"
                and self.solver.linear_solver != "multigrid"):
            raise ValueError(
                "time.dt = \"auto\" runs the projection scheme's steps inside the compiled "
                f"core, with the multigrid solver; solver.linear_solver = "
                f"{self.solver.linear_solver!r} solves from Python one fixed step at a time: "
                "set solver.linear_solver = \"multigrid\", or give time.dt a number")
        dt = time_step(self)
        if self.time.end < dt * (1 - 1e-9):
            raise ValueError(
                f"time.end = {self.time.end:g} s is shorter than one time step of {dt:.3g} s "
                f"(time.dt = {self.time.dt!r}); a run takes at least one step: give a later "
                "time.end, or a smaller time.dt")
        steps = self.time.end / dt
        if not steps <= MAX_STEPS:
            raise ValueError(
                f"time.end = {self.time.end:g} s is {steps:.3g} steps of {dt:.3g} s, more than "
                f"the {MAX_STEPS:,} a run can take (checkpoints are numbered by step with 9 "
                "digits; at a few milliseconds per step that many steps take weeks): give a "
                "shorter time.end, or a larger time.dt")
        if self.time.dt != "auto" and self.solver.scheme == "explicit":
            limit = case_stable_time_step(self)
            if self.time.dt > limit:
                c = sound_speed(self.material.bulk_modulus, self.material.density)
                raise ValueError(
                    f"time.dt = {self.time.dt:g} s is above the stable step of the explicit "
                    f"scheme, {limit:.4g} s = grid.spacing / (sound speed + initial speed) = "
                    f"{self.grid.spacing:g} / ({c:.4g} + {initial_speed(self):.3g}) m/s; set "
                    f"time.dt to at most {limit:.4g} s, or time.dt = \"auto\" (which uses "
                    f"time.safety_factor = {self.time.safety_factor:g} of it), or lower "
                    "material.bulk_modulus")
        if self.time.dt != "auto" and self.output.interval < self.time.dt * (1 - 1e-9):
            raise ValueError(
                f"output.interval = {self.output.interval:g} s is shorter than time.dt = "
                f"{self.time.dt:g} s; make it at least one time step")
        # once checked: mesh files by absolute path, so that the resolved case
        # (summary.json) finds them from anywhere (as probes' data)
        for spec in [*self.bodies, *self.obstacles]:
            if spec.type == "mesh" and not Path(spec.path).expanduser().is_absolute():
                path = (self.base_dir / Path(spec.path).expanduser()).resolve()
                if path.is_file():
                    object.__setattr__(spec, "path", str(path))
        return self


# --------------------------------------------------------------------------- loading

def _read_toml(path):
    path = Path(path)
    try:
        with open(path, "rb") as f:  # any file: also a pipe, e.g. <(sed ... case.toml)
            raw = f.read(MAX_CASE_BYTES + 1)
    except FileNotFoundError:
        raise CaseError(f"Case file {path} does not exist. Give the path of a .toml case file, "
                        "e.g. examples/dam_break.toml.") from None
    except IsADirectoryError:
        raise CaseError(f"Case file {path} is a folder; give the path of a .toml case "
                        "file.") from None
    except OSError as err:
        raise CaseError(f"Case file {path} cannot be read: {err.strerror}.") from None
    if len(raw) > MAX_CASE_BYTES:
        raise CaseError(f"Case file {path} is larger than {MAX_CASE_BYTES // 2**20} MiB, so it "
                        "is not a case file (a case is a page of TOML text); give the path of "
                        "a .toml case file, e.g. examples/dam_break.toml.")
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError:
        raise CaseError(f"Case file {path} is not a UTF-8 text file; give a TOML case file, "
                        "e.g. examples/dam_break.toml.") from None
    if "\0" in text:
        raise CaseError(f"Case file {path} holds NUL bytes, so it is not a text file; give a "
                        "TOML case file, e.g. examples/dam_break.toml.")
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as err:
        raise CaseError(f"Case file {path} is not valid TOML: {err}. Fix the syntax there "
                        "(strings in quotes, lists in [ ], one key = value per line).") from None


def _parse_value(text):
    """A --set value: any TOML value, or a bare word taken as a string."""
    try:
        return tomllib.loads(f"v = {text}")["v"]
    except tomllib.TOMLDecodeError:
        return text


def _model_for(section):
    """The pydantic model describing a nested dict at this position, if any."""
    return section if isinstance(section, type) and issubclass(section, BaseModel) else None


def _models_of(annotation):
    """The pydantic models a field's annotation (or a list's item) may hold: one, the
    members of a union (the shapes of bodies and obstacles), or none."""
    origin = typing.get_origin(annotation)
    if origin is Annotated:
        return _models_of(typing.get_args(annotation)[0])
    if origin is Union:
        return [m for a in typing.get_args(annotation) for m in _models_of(a)]
    model = _model_for(annotation)
    return [model] if model is not None else []


def _item(annotation):
    """(is a list, the annotation of an item or the annotation itself)."""
    if typing.get_origin(annotation) is list:
        return True, typing.get_args(annotation)[0]
    return False, annotation


def key_reference():
    """Every case key with its default, whether it is required, and its description."""
    rows = []

    seen = set()

    def walk(model, prefix):
        for name, field in model.model_fields.items():
            is_list, inner = _item(field.annotation)
            subs = _models_of(inner)
            if subs:
                for sub in subs:  # the shapes of a body: their keys, each once
                    walk(sub, f"{prefix}{name}.N." if is_list else f"{prefix}{name}.")
                continue
            if f"{prefix}{name}" in seen:
                continue
            seen.add(f"{prefix}{name}")
            required = field.is_required()
            default = None if required else field.get_default()
            if model is Solver and name in FORMULATIONS["mpmflow"]:
                default = FORMULATIONS["mpmflow"][name]
            rows.append({"key": f"{prefix}{name}", "required": required, "default": default,
                         "example": (field.examples or [None])[0],
                         "description": field.description or ""})

    walk(Case, "")
    return rows


_REFERENCE = {row["key"]: row for row in key_reference()}
KNOWN_KEYS = list(_REFERENCE)
# lists of tables an override may replace whole, e.g. {"probes": [{"name": ..., ...}]} or
# --set 'probes=[{name = "p1", quantity = "pressure", position = [0.42, 0.01]}]'
LIST_KEYS = ("bodies", "obstacles", "probes")


def _generic(dotted):
    """bodies.0.max -> bodies.N.max"""
    return ".".join("N" if part.isdigit() else part for part in dotted.split("."))



def _suggest(dotted):
    parts = dotted.split(".")
    if parts[0] not in Case.model_fields:
        # a misspelt section or list ([[obstacle]]): the whole key's nearest match would be
        # some key under it (obstacles.0.min), not the name the user meant
        top = difflib.get_close_matches(parts[0], list(Case.model_fields), n=1, cutoff=0.6)
        fixed = ".".join(top + parts[1:])
        if top and (len(parts) == 1 or _generic(fixed) in KNOWN_KEYS):
            tables = f" ([[{top[0]}]] tables)" if len(parts) == 1 and top[0] in LIST_KEYS \
                else ""
            return f" Did you mean `{fixed}`{tables}?"
    match = difflib.get_close_matches(_generic(dotted), KNOWN_KEYS, n=1, cutoff=0.6)
    if not match:
        return ""
    return f" Did you mean `{match[0].replace('.N.', '.' + _index(dotted) + '.')}`?"


def _index(dotted):
    parts = [p for p in dotted.split(".") if p.isdigit()]
    return parts[0] if parts else "0"


def apply_overrides(data, overrides):
    """Apply overrides to the raw case dict, in place: ``key=value`` strings (dotted keys,
    TOML values, as --set takes them) or a dict {dotted key: Python value}."""
    if isinstance(overrides, dict):
        items = [(str(k), v, False) for k, v in overrides.items()]
    elif isinstance(overrides, str):
        raise CaseError(f"overrides = {overrides!r}: give a list of \"key=value\" strings or "
                        "a dict {\"dotted.key\": value}, e.g. {\"grid.spacing\": 0.008}.")
    else:
        items = []
        for item in overrides:
            if not isinstance(item, str) or "=" not in item:
                raise CaseError(f"--set {item!r} is not of the form dotted.key=value, e.g. "
                                "--set grid.spacing=0.008.")
            key, text = item.split("=", 1)
            items.append((key, text, True))
    for key, value, parse in items:
        key = key.strip()
        label = "--set" if parse else "override"
        parts = key.split(".")
        node = data
        for depth, part in enumerate(parts[:-1]):
            if isinstance(node, list):
                _check_index(label, key, parts, depth, node, value)
                node = node[int(part)]
            else:  # a list of tables the case file leaves out starts empty
                node = node.setdefault(part, [] if depth == 0 and part in LIST_KEYS else {})
            if not isinstance(node, (dict, list)):
                raise CaseError(f"{label} {key}: `{'.'.join(parts[:depth + 1])}` is a value, not a "
                                "section." + _suggest(key))
        if isinstance(node, list) and len(parts) == 2:  # a whole table: obstacles.0={...}
            _check_index(label, key, parts, 1, node, value, append=True)
            node[int(parts[1]):int(parts[1]) + 1] = [_parse_value(value.strip()) if parse
                                                     else value]
            continue
        if _generic(key) not in KNOWN_KEYS and key not in LIST_KEYS:
            raise CaseError(f"{label} {key}: unknown case key `{key}`.{_suggest(key)} "
                            "Run `mpmflow keys` for the list of keys.")
        node[parts[-1]] = _parse_value(value.strip()) if parse else value


def _check_index(label, key, parts, depth, entries, value, append=False):
    """parts[depth] indexes the list ``entries`` (the tables of parts[depth - 1]), or, for a
    whole table (``append``), is the next index; CaseError naming the list otherwise."""
    name, part = ".".join(parts[:depth]), parts[depth]
    n = len(entries)
    if part.isdigit() and (int(part) < n or append and int(part) == n):
        return
    after = ".".join(parts[depth + 1:])
    shown = value.strip() if isinstance(value, str) else "..."
    table = _TABLE_EXAMPLES.get(name, "{...}")
    if n == 0:
        raise CaseError(f"{label} {key}: `{name}` has no entries; add one first, e.g. --set "
                        f"'{name}.0={table}', or a [[{name}]] table in the case file.")
    example = f"{name}.{n - 1}" + (f".{after}" if after else "")
    more = "" if after else f", or --set '{name}.{n}={table}' to add one"
    raise CaseError(f"{label} {key}: `{name}` has {n} entr{'y' if n == 1 else 'ies'}; use an "
                    f"index from 0 to {n - 1}, e.g. --set {example}={shown}{more}.")


_TABLE_EXAMPLES = {  # a table of each list, for messages
    "bodies": '{type = "box", min = [...], max = [...]}',
    "obstacles": '{type = "box", min = [...], max = [...]}',
    "probes": '{name = "p1", quantity = "pressure", position = [...]}'}


def _shape_loc(parts):
    """(loc without the shape tags pydantic puts after a body's or obstacle's index, the
    shape type of that table or None): ("bodies", 0, "disc", "radius") -> bodies.0.radius."""
    out, kind = [], None
    for p in parts:
        if isinstance(p, str) and p in SHAPE_TYPES and out and isinstance(out[-1], int):
            kind = p
            continue
        out.append(p)
    return ".".join(str(p) for p in out), kind


def _shape_keys(kind, table):
    models = {"bodies": Body, "obstacles": Obstacle}[table]
    model = _models_of(models)[SHAPE_TYPES.index(kind)]
    return ", ".join(model.model_fields)


def _format_error(err, source):
    lines = []
    for e in err.errors():
        loc, kind = _shape_loc(e["loc"])
        if e["type"] == "union_tag_invalid":
            given = e.get("input", {}).get("type") if isinstance(e.get("input"), dict) else None
            lines.append(f"`{loc}.type` = {given!r} is not a shape: give {loc}.type one of "
                         + ", ".join(f'"{t}"' for t in SHAPE_TYPES) + " (\"box\" when left "
                         "out); `mpmflow keys` lists each shape's keys.")
            continue
        if e["type"] == "extra_forbidden":
            table = loc.split(".")[0]
            if kind is not None and table in ("bodies", "obstacles") \
                    and _generic(loc) in KNOWN_KEYS:
                lines.append(f"`{loc}` is not a key of a \"{kind}\" ({table} of type "
                             f"\"{kind}\" take {_shape_keys(kind, table)}): remove it, or "
                             "set the type of shape it belongs to.")
                continue
            lines.append(f"unknown key `{loc}`.{_suggest(loc)}")
            continue
        if e["type"] == "missing":
            desc = _describe(loc)
            lines.append(f"missing key `{loc}`{': ' + desc if desc else ''}")
            continue
        msg = e["msg"].removeprefix("Value error, ").rstrip(".")
        key, entry = loc, ""
        while _generic(key) not in _REFERENCE and key.rsplit(".", 1)[-1].isdigit():
            key = key.rsplit(".", 1)[0]  # an entry of a list value: name the key
            entry = f" (entry {loc[len(key) + 1:]} of {key})"
        row = _REFERENCE.get(_generic(key))
        if row is not None:
            fix = f" Set a valid value, e.g. {key} = {_example(row)}." if _example(row) else ""
            lines.append(f"`{loc}`{entry} = {e.get('input')!r} is not allowed: {msg}. {key}: "
                         f"{row['description']}{fix}")
        elif _is_section(loc) and e["type"] == "model_type":
            lines.append(f"`{loc}` = {e.get('input')!r} is not allowed: {loc} is a section; "
                         f"write it as a [{loc}] table of keys (`mpmflow keys` lists them).")
        else:
            lines.append(f"{loc}: {msg}." if loc else f"{msg}.")
    head = f"Invalid case {source}: " if source else "Invalid case: "
    return CaseError(head + " ".join(lines) + " See the case-file reference, docs/reference.md "
                     "(or `mpmflow keys`).")


def _is_section(loc):
    parts = [p for p in loc.split(".") if not p.isdigit()]
    model = Case
    for part in parts:
        field = model.model_fields.get(part)
        if field is None:
            return False
        models = _models_of(_item(field.annotation)[1])
        if not models:
            return False
        model = models[0]
    return True


def _describe(loc):
    return _REFERENCE.get(_generic(loc), {}).get("description", "")


def _example(row):
    value = row["example"] if row["example"] is not None else row["default"]
    if value is None:
        return ""
    return f'"{value}"' if isinstance(value, str) else str(value).lower() \
        if isinstance(value, bool) else str(value)


def _check_probe_data(k, probe, folder):
    """probes.k.data: its file exists and names its columns (ValueError otherwise); the path
    is made absolute (relative to ``folder``, the case file's, else the working folder), so
    that the resolved case in summary.json finds it from anywhere."""
    data = probe.data
    path = Path(data.path).expanduser()
    if not path.is_absolute():
        path = (Path(folder) if folder is not None else Path.cwd()) / path
    path = path.resolve()
    key = f"probes.{k}.data"
    try:
        with open(path, encoding="utf-8") as f:
            first = f.readline()
    except OSError as err:
        raise ValueError(
            f"{key}.path = {data.path!r}: the file {path} cannot be read ({err.strerror}); give "
            "the path of the measured series' CSV file, relative to the case file's folder")
    except UnicodeDecodeError:
        raise ValueError(f"{key}.path = {data.path!r}: {path} is not a text file; give the "
                         "path of the measured series' CSV file (a header line, then numbers)")
    names = [c.strip().strip('"') for c in first.rstrip("\r\n").split(",")]
    for field in ("time_column", "column"):
        name = getattr(data, field)
        if name not in names:
            raise ValueError(
                f"{key}.{field} = {name!r} is not a column of {path.name}, whose header names "
                + ", ".join(repr(n) for n in names[:20]) + (" ..." if len(names) > 20 else "")
                + f"; set {key}.{field} to one of them, exactly as written")
    object.__setattr__(data, "path", str(path))


def validate(data, source="", base_dir=None):
    """A Case from the case's dict; ``base_dir``: the folder relative paths (mesh files,
    probes' data) start from, the case file's (None: the folder of ``source`` when it names
    a file, else the current folder)."""
    if base_dir is None and source and not source.startswith("("):
        base_dir = str(Path(source).resolve().parent)
    try:
        return Case.model_validate(data, context={"base_dir": base_dir, "folder": base_dir})
    except ValidationError as err:
        raise _format_error(err, source) from None


def _folder_of(path):
    """The folder of a case file, where its relative paths start; the current folder for a
    case that is not a regular file (a pipe such as <(sed ... case.toml))."""
    path = Path(path)
    return path.resolve().parent if path.is_file() else Path.cwd()


def load_case(path, overrides=()):
    """Read, override and validate a case file; raises CaseError with a user message.

    ``overrides``: what --set takes, as a list of "dotted.key=value" strings (TOML values),
    or a dict {"dotted.key": value} of Python values, e.g. {"grid.spacing": 0.008,
    "bodies.0.max": [0.1, 0.2]}. Either way the values pass the same checks as the file's."""
    data = _read_toml(path)
    apply_overrides(data, overrides)
    return validate(data, source=str(path), base_dir=_folder_of(path))


def validate_case(data):
    """A case from a dict of sections (as the TOML file would hold them), or a Case to check
    again as a whole (see ``revalidate``); CaseError with a user message."""
    if isinstance(data, Case):
        return revalidate(data)
    if not isinstance(data, dict):
        raise CaseError(f"expected a dict of case sections, got {type(data).__name__}.")
    return validate(data)


def revalidate(case):
    """The case validated again as a whole: the cross-field checks (bodies in the domain and
    apart, time step against end, ...) for a case whose fields were changed after loading
    (an assignment checks only its own section). CaseError when it no longer holds."""
    if not isinstance(case, Case):
        raise CaseError(f"expected a case (mpmflow.load_case(...)), got {type(case).__name__}; "
                        "load one with mpmflow.load_case(path, overrides).")
    return validate(case.model_dump(), source="(changed after loading)",
                    base_dir=case._base_dir)


def resolved(case):
    """The fully resolved case as plain data (defaults filled in)."""
    return case.model_dump(mode="json")



def reference_markdown():
    """The case-file reference as a Markdown table (generated into the README)."""
    lines = ["| key | default | meaning |", "|---|---|---|"]
    for row in key_reference():
        if row["required"]:
            default = "**required**"
        elif isinstance(row["default"], bool):
            default = f"`{str(row['default']).lower()}`"
        elif isinstance(row["default"], str):
            default = f'`"{row["default"]}"`' if row["default"] else '`""`'
        elif row["default"] is None:
            default = "(see meaning)"
        else:
            default = f"`{row['default']}`"
        lines.append(f"| `{row['key']}` | {default} | {row['description']} |")
    return "\n".join(lines)


def reference_page():
    """docs/reference.md: the case-file reference page, generated from the schema."""
    return (
        "# Case-file reference\n\n"
        "<!-- generated by scripts/update_readme_reference.py from src/mpmflow/case.py; "
        "do not edit -->\n\n"
        "A case is a TOML file; all quantities are SI (m, s, kg, Pa). The domain is "
        "[0, size] and its boundaries are walls. `bodies` is a list of `[[bodies]]` tables "
        "(`bodies.N.` below is the N-th, from 0), `obstacles` and `probes` likewise; a body "
        "or obstacle takes the keys of its shape (`type`) besides its own. Any key can be "
        "overridden on the command line with `--set dotted.key=value`; `mpmflow keys` prints "
        "this list. Unknown keys "
        "are errors (with a suggestion), and a bad value stops with a message naming the "
        "key, the value, the allowed range and the fix (exit code 2).\n\n"
        + reference_markdown() + "\n")
