"""The case file's sections (SI units throughout): one pydantic model per [table], each
field's description the single source of the case-file reference (docs/reference.md).
The domain (its size, walls and periodic axes) is in ``case.domain``, the shapes of
bodies and obstacles in ``case.shapes``; the whole case and its
cross-field rules in ``case.model``."""

import math
from typing import Literal

from pydantic import BaseModel, ConfigDict, Field, field_validator, model_validator
from typing_extensions import Self

from .. import materials

# checkpoint files are numbered by step with 9 digits (checkpoint_NNNNNNNNN.npz): the most
# steps a run can take. (At 2 ms per step, the cost of a small case, that is 23 days.)
MAX_STEPS = 999_999_999
COURANT = 1.0  # time.courant's default (docs/method.md, "Adaptive steps")
MAX_DT = 1e-2  # s: time.max_dt's default, the paper's step for its dam break
MAX_CASE_BYTES = 16 * 2**20  # a case file is a page of TOML; anything larger is not one
# the scales of a case that a flow of liquid or grains can have (the keys' descriptions say
# why); beyond them the input is a mistake of units, and the pressure solve overflowed
MIN_DENSITY = 1.0  # kg/m^3: about the air the method leaves out (1.2)
MAX_DENSITY = 1e5  # kg/m^3: four times osmium, the densest element
MAX_GRAVITY = 1e4  # m/s^2: about 1,000 g, geotechnical centrifuges' top
MAX_PRESSURE = 1e12  # Pa: rho |g| H; water's bulk modulus is 2.2e9 Pa


class Section(BaseModel):
    """A table of the case file: unknown keys refused, values checked on assignment too,
    and values kept as the types TOML gives them (strict): a number is an integer or a
    float, never a boolean or a string in quotes, and a boolean is true or false, never 1
    or "no" (pydantic's lax mode had turned `particles_per_cell = true` into 1 and
    `snapshots = "no"` into false without a word). An integer stands for a float."""

    model_config = ConfigDict(
        extra="forbid", validate_assignment=True, allow_inf_nan=False, strict=True
    )


class GridSettings(Section):
    spacing: float = Field(
        description="Cell size of the background grid (m). Walls lie on grid lines: a side of "
        "the domain that is not a whole number of cells is extended to the next whole cell "
        "(reported at start and in summary.json).",
        gt=0,
        examples=[0.004],
    )


class Material(Section):
    model: Literal[tuple(materials.MATERIALS)] = Field(  # type: ignore[valid-type]
        "water",
        description='Constitutive model: "water" (inviscid, the default), '
        '"newtonian" (viscosity), "herschel_bulkley" (yield-stress material; Bingham '
        "with flow_index = 1: consistency, yield_stress, flow_index, max_viscosity) or "
        '"mu_i" (dense granular flow: friction_static, friction_limit, '
        "inertial_number_ref, grain_diameter, grain_density, max_viscosity); or a solid "
        'with a stress history on its particles: "elastic" (shear_modulus), "von_mises" '
        "(undrained clay: shear_modulus, undrained_strength, strength_gradient, "
        'strength_datum) or "drucker_prager" (frictional soil matched to Mohr-Coulomb in '
        "plane strain: shear_modulus, friction_angle, cohesion, tension_cutoff); or a "
        'saturated soil, "poroelastic" (a linear elastic skeleton with pore water flowing '
        "through it by Darcy's law: shear_modulus, poisson_ratio, permeability, "
        'water_density; docs/method.md, "Saturated soil"). Each takes '
        "only its own parameters; the viscous stress is solved implicitly (docs/method.md, "
        '"Viscous materials"), and so is a solid\'s elastic step (docs/method.md, '
        '"Solids"); every material is incompressible (a saturated soil\'s grains and water '
        "are: it changes its volume only as its water drains).",
    )
    density: float = Field(
        1000.0,
        ge=MIN_DENSITY,
        le=MAX_DENSITY,
        description="Density (kg/m^3); with model = "
        '"mu_i" the bulk density, solid fraction x grain_density. From '
        f"{MIN_DENSITY:g} to {MAX_DENSITY:g} kg/m^3: the method leaves out the air "
        "above the material (1.2 kg/m^3), which only a much denser material allows, and no "
        "material is denser than a few times osmium (22,590 kg/m^3; mercury: 13,546); "
        "outside the range the value is a mistake of units (at 1e300 the pressure solve "
        "overflowed).",
    )
    viscosity: float = Field(
        0.0,
        ge=0,
        description="Dynamic viscosity (Pa s) of model = "
        '"newtonian" (water at 20 C: 1.0e-3); 0 for "water".',
    )
    consistency: float = Field(
        1.0,
        description="Consistency K (Pa s^n) of model = "
        '"herschel_bulkley": |tau| = yield_stress + K rate^n '
        "where the material flows (the plastic viscosity when n = 1).",
    )
    yield_stress: float = Field(0.0, description='Yield stress (Pa) of model = "herschel_bulkley".')
    flow_index: float = Field(
        1.0,
        description='Flow index n of model = "herschel_bulkley" (1: Bingham; < 1 shear-thinning).',
    )
    max_viscosity: float = Field(
        1e5,
        description="Cap of the effective viscosity (Pa s) of models "
        '"herschel_bulkley" and "mu_i" (bi-viscous regularisation): below the yield '
        "the material creeps at rate |tau| / max_viscosity instead of standing still. Larger "
        "is stiffer and costs more iterations of the viscous solve.",
    )
    friction_static: float = Field(
        0.38,
        description='mu_s of model = "mu_i": the '
        "friction coefficient at rest (tan of the angle below which "
        "a layer stops; glass beads: 0.38).",
    )
    friction_limit: float = Field(
        0.64,
        description='mu_2 of model = "mu_i": the friction '
        "coefficient at large inertial number (glass beads: 0.64).",
    )
    inertial_number_ref: float = Field(
        0.279, description='I0 of model = "mu_i" (glass beads: 0.279).'
    )
    grain_diameter: float = Field(
        0.53e-3, description='Grain diameter d (m) of model = "mu_i" (glass beads: 0.53e-3).'
    )
    grain_density: float = Field(
        2450.0,
        description="Density of the grains (kg/m^3) of "
        'model = "mu_i"; the solid fraction is density / '
        "grain_density (glass beads: 2450).",
    )
    shear_modulus: float = Field(
        1e6,
        description='Shear modulus G (Pa) of the solids "elastic", "von_mises" and '
        "\"drucker_prager\": s = 2 G (deviatoric strain); Young's modulus is 3 G (Poisson's "
        "ratio 0.5: the solid is incompressible). It sets the shear-wave speed "
        "sqrt(G / density) and with it a solid's step, 0.5 grid.spacing / sqrt(G / "
        'density): time.dt = "auto" takes it, at which the shear waves are followed; a '
        "longer fixed time.dt solves the elastic step and the projection as one system "
        '(stable at any step, damping the waves; no obstacles yet: docs/method.md, "Solids").',
    )
    undrained_strength: float = Field(
        20e3,
        description='Undrained shear strength s_u (Pa) of model = "von_mises" at '
        "strength_datum (Tresca's in plane strain: (sigma_1 - sigma_3) / 2 <= s_u).",
    )
    strength_gradient: float = Field(
        0.0,
        description='Growth of s_u with depth (Pa/m) of model = "von_mises": s_u + '
        "strength_gradient x (strength_datum - height) below strength_datum.",
    )
    strength_datum: float = Field(
        0.0,
        description='Height (m, along the last axis) of model = "von_mises" where s_u is '
        "undrained_strength; the strength grows below it by strength_gradient.",
    )
    friction_angle: float = Field(
        30.0, description='Friction angle phi (degrees) of model = "drucker_prager".'
    )
    cohesion: float = Field(0.0, description='Cohesion c (Pa) of model = "drucker_prager".')
    tension_cutoff: float = Field(
        0.0,
        description='Tension (Pa) model = "drucker_prager" bears before it parts: where the '
        "pressure is below -tension_cutoff the soil carries no deviatoric stress.",
    )
    poisson_ratio: float = Field(
        0.3,
        description='Poisson\'s ratio nu of the drained skeleton of model = "poroelastic" '
        "(0 to 0.5, 0.5 excluded; soils 0.2-0.35): with shear_modulus it gives the "
        "skeleton's bulk stiffness, lambda = 2 G nu / (1 - 2 nu), and its constrained "
        "modulus lambda + 2 G, which sets the consolidation coefficient c_v = k (lambda + "
        "2 G) / (water_density g_n).",
    )
    permeability: float = Field(
        1e-6,
        description='Hydraulic conductivity k (m/s) of model = "poroelastic" (Darcy\'s law: '
        "the water's flux relative to the skeleton is -k / (water_density g_n) (grad p - "
        "water_density g), g_n = 9.80665 m/s^2 whatever physics.gravity; clay 1e-9, silt "
        "1e-7, sand 1e-4). The step does not depend on it.",
    )
    initial_stress: Literal["zero", "geostatic"] = Field(
        "zero",
        description='The effective stress model = "poroelastic" starts from: "zero", or '
        '"geostatic", the skeleton carrying its buoyant weight at rest: sigma\'_v = -(density '
        "- water_density) |g| d, d the depth below the soil's top in the particle's column "
        "(gravity along the last axis), and sigma'_h = nu / (1 - nu) sigma'_v (the confined "
        "elastic skeleton's K0). A bed under still water then starts, and stays, at rest.",
    )
    water_density: float = Field(
        1000.0,
        description='Density (kg/m^3) of the pore water of model = "poroelastic"; '
        "material.density is then the saturated soil's (grains and water).",
    )
    bulk_modulus: float = Field(
        2.2e9,
        gt=0,
        description="Bulk modulus K (Pa) of the weakly compressible material of "
        "the explicit scheme, p = -K * volumetric strain (water: 2.2e9). It sets the sound "
        "speed sqrt(K / density) and with it the stable time step. Not used by the projection "
        "scheme, whose material is incompressible.",
    )

    @model_validator(mode="after")
    def _model_parameters(self) -> Self:
        materials.check(self)
        return self


class Physics(Section):
    gravity: list[float] = Field(
        [0.0, -9.81],
        description="Gravitational acceleration (m/s^2); "
        "the default points down the last axis, [0, 0, -9.81] in 3D. Its magnitude is at "
        f"most {MAX_GRAVITY:g} m/s^2 (about 1,000 g, the top of the geotechnical "
        "centrifuges that scale flows of soil and water up by g); more is a mistake of "
        "units (at 1e300 the pressure solve overflowed).",
        min_length=2,
        max_length=3,
    )

    @field_validator("gravity")
    @classmethod
    def _magnitude(cls, gravity: list[float]) -> list[float]:
        g = math.hypot(*gravity)  # (hypot: no overflow on the way)
        if not g <= MAX_GRAVITY:
            raise ValueError(
                f"its magnitude is {g:.4g} m/s^2, above {MAX_GRAVITY:g} m/s^2; give the "
                "acceleration in m/s^2 (Earth: 9.81)"
            )
        return gravity


class Time(Section):
    dt: Literal["auto"] | float = Field(
        description='Time step (s), or "auto". With "auto" the projection scheme sets '
        "every step from the particles' speeds: dt = time.courant grid.spacing / max |v_p|, "
        "at most time.max_dt, the last steps before an output time shortened to land on it; "
        "the explicit scheme takes its stable step h / (c + |v|) (sound speed "
        "c = sqrt(K / density)) times time.safety_factor.",
        examples=[1e-3],
    )
    safety_factor: float = Field(
        0.5,
        gt=0,
        le=1,
        description="Fraction of the stable explicit time step used by "
        'time.dt = "auto" (dimensionless).',
    )
    courant: float = Field(
        COURANT,
        gt=0,
        le=10,
        description="Courant number of the projection scheme's steps "
        'with time.dt = "auto": the fastest particle crosses this many cells per step '
        "(dimensionless; measured against the dam break's validation rows, docs/method.md).",
    )
    max_dt: float = Field(
        MAX_DT,
        gt=0,
        description="Longest step of the projection scheme with time.dt = "
        '"auto" (s): the step of a flow at rest, and the cap when it moves slowly.',
    )
    end: float = Field(
        description="Simulated time at which the run stops (s).", gt=0, examples=[1.0]
    )

    @model_validator(mode="after")
    def _positive(self) -> Self:
        if self.dt != "auto" and self.dt <= 0:
            raise ValueError('time.dt must be greater than 0 (seconds), or "auto"')
        return self


class Output(Section):
    interval: float = Field(
        0.01,
        gt=0,
        description="Simulated time between rows of timeseries.csv (s). The steps "
        "between two output times are all equal and at most time.dt, so every output time is "
        "landed on exactly.",
    )
    snapshot_interval: float | None = Field(
        None,
        gt=0,
        description="Simulated time between particle snapshots (s); defaults to "
        "output.interval. Snapshots are written at the first output time at or after each "
        "multiple (so an interval shorter than output.interval means every output).",
    )
    snapshots: bool = Field(
        True,
        description="Write particle snapshots (VTU files and a "
        "particles.pvd time series for ParaView).",
    )
    centre_of_mass: bool = Field(
        False,
        description="Write the water's centre of mass (m) at the output times into "
        "centre_of_mass.csv.",
    )


class Checkpoint(Section):
    interval: float = Field(
        0.1,
        gt=0,
        description="Simulated time between checkpoints (s), written at the first "
        "output time at or after each multiple (every output for an interval shorter than "
        "output.interval), at the end of the run and when it is interrupted (Ctrl-C, "
        "SIGTERM). A checkpoint (checkpoint_NNNNNNNNN.npz in the output "
        "folder, the latest two kept; on MPI ranks with one piece a rank beside it, "
        "checkpoint_NNNNNNNNN_rRRRR.npz) holds everything needed to continue: `mpmflow run CASE "
        "--out DIR --restart` resumes from the latest and reproduces the uninterrupted run "
        "bit for bit.",
    )


class ProbeData(Section):
    path: str = Field(
        description="The measured series' CSV file (a header line naming the columns, then "
        "rows of numbers separated by commas), relative to the case file's folder (to the "
        "working folder for a case built in Python). Checked when the case is loaded: in "
        "the two columns the probe reads every row holds a finite number (no text, nan or "
        "inf) and the times do not decrease; a line that breaks this is refused by number.",
        examples=[
            "../shared/data/validation/spheric_test2_kleefsman2005_marin_exp_P1-P8_H1-H4.csv"
        ],
    )
    column: str = Field(
        description="The header of the file's column that holds the measured values, in the "
        "probe's unit (Pa for pressure, m for level).",
        examples=["P1 [Pa]"],
    )
    time_column: str = Field(
        "time [s]", description="The header of the file's column of times (s)."
    )


class Probe(Section):
    name: str = Field(
        description="Name of the probe: its column in probes.csv (letters, digits, _ . + -).",
        pattern=r"^[A-Za-z0-9_.+-]{1,64}$",
        examples=["sensor_1"],
    )
    quantity: Literal["pressure", "level"] = Field(
        description="What the probe measures at every output time, into probes.csv: "
        '"pressure" = the water\'s pressure (Pa) at position, from the particles in a '
        "window (a square, in 3D a cube, of side probes.N.window) around it: centred on "
        "position, except that along an axis where position lies on a wall the window lies "
        "on the water's side (one window in from the wall), and cut at any other wall; read "
        "as probes.N.estimate says; 0 when no particle is in the window (a dry sensor reads "
        'the atmosphere\'s gauge pressure). "level" = a water-level gauge on the vertical '
        "line through position (x in 2D; x and y in 3D): the level (m) above the gauge's foot "
        "position, read from the cell volume fraction interpolated linearly (bilinearly in "
        "3D) between the cell columns around the line, as probes.N.gauge says.",
        examples=["pressure"],
    )
    position: list[float] = Field(
        description='Where the probe is (m): the sensor\'s point for "pressure", the foot of '
        'the gauge for "level" (e.g. [x, 0] on the floor in 2D, [x, y, 0] in 3D). Inside '
        "the domain.",
        min_length=2,
        max_length=3,
        examples=[[0.42, 0.01]],
    )
    window: float | None = Field(
        None,
        gt=0,
        description="Side of a pressure probe's window (m); none = the fewest "
        "whole grid cells that hold the 2 (D + 1) particles of a fit at the sparsest body's "
        "particles_per_cell (one cell at 3 or more per axis in 2D, 2 or more in 3D; two "
        "cells at the default 2 in 2D). A larger window averages more particles (less "
        "noise, less resolution). At least the particles' spacing (grid.spacing / "
        "particles_per_cell of the densest body): a narrower window holds one particle at "
        "most and reads 0 in water most of the time.",
    )
    estimate: Literal["fit", "mean"] = Field(
        "fit",
        description='How a pressure probe reads its window\'s particles: "fit" = '
        "the value at position of the plane p = a + b.(x - position) fitted to them by least "
        "squares, the pressure AT the point (exact on a hydrostatic column, also for a sensor "
        "on a wall, whose window lies beside it; falls back to the mean with too few "
        "particles or particles in one layer, and reads 0 for a negative value among "
        'pressures that are not, each counted in summary.json\'s caps_and_fallbacks); "mean" = their mean pressure, the pressure at their '
        "centre (half a window from a wall sensor: rho g window/2 low on the column at "
        "rest).",
    )
    gauge: Literal["integral", "first_drop"] = Field(
        "integral",
        description="How a level probe reads the volume fraction f on its line: "
        '"integral" = the integral of f from the foot up (m), the water\'s depth gathered '
        "into one layer, as a resistance or capacitance wave probe reads its wetted wire "
        "(and OpenFOAM's interfaceHeight): a splash or spray above the layer counts by its "
        "volume, an air pocket under the surface counts out by its volume, an aerated cell "
        'at the foot lowers it by its air only; "first_drop" = the height above the foot '
        "where f first drops below 1/2 going up (the top of the first layer: 0 when the "
        "foot's cell is less than half full, splashes above the layer not counted). Level "
        "probes only.",
    )
    data: ProbeData | None = Field(
        None,
        description="The measured series to compare with ([probes.data] table: path, "
        "column, time_column): `mpmflow plot` draws it beside the probe's.",
    )


class Execution(Section):
    threads: Literal["auto"] | int = Field(
        "auto",
        description='Threads of the compiled kernels: "auto" uses the cores that '
        "other programs leave idle, measured when the run starts and again about every "
        "second at output times (a run beside another busy program drops to fewer threads "
        "instead of waiting for a shared core), or a number, fixed for the whole run. The "
        'environment variable MPMFLOW_THREADS, when set, takes the place of "auto". '
        "Results do not depend on the number of threads. May change on --restart.",
    )

    @model_validator(mode="after")
    def _positive(self) -> Self:
        if self.threads != "auto" and self.threads < 1:
            raise ValueError('execution.threads must be "auto" or at least 1')
        return self


# The formulation presets: defaults of the settings that separate mpmflow's projection from
# the plain reading of the paper (measured against each other in docs/variants.md and, for the
# volume correction and the sparse threshold, in docs/method.md).
