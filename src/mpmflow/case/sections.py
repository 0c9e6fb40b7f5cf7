"""The case file's sections (SI units throughout): one pydantic model per [table], each
field's description the single source of the case-file reference (docs/reference.md).
The domain (its size, walls and periodic axes) is in ``case.domain``, the shapes of
bodies and obstacles in ``case.shapes``; the whole case and its
cross-field rules in ``case.model``."""

from typing import Literal

from pydantic import BaseModel, ConfigDict, Field, PrivateAttr, model_validator

from .. import materials

# checkpoint files are numbered by step with 9 digits (checkpoint_NNNNNNNNN.npz): the most
# steps a run can take. (At 2 ms per step, the cost of a small case, that is 23 days.)
MAX_STEPS = 999_999_999
COURANT = 1.0  # time.courant's default (docs/method.md, "Adaptive steps")
MAX_DT = 1e-2  # s: time.max_dt's default, the paper's step for its dam break
MAX_CASE_BYTES = 16 * 2**20  # a case file is a page of TOML; anything larger is not one


class Section(BaseModel):
    """A table of the case file: unknown keys refused, values checked on assignment too."""

    model_config = ConfigDict(extra="forbid", validate_assignment=True, allow_inf_nan=False)


class GridSettings(Section):
    spacing: float = Field(
        description="Cell size of the background grid (m). Walls lie on grid lines: a side of "
        "the domain that is not a whole number of cells is extended to the next whole cell "
        "(reported at start and in summary.json).", gt=0, examples=[0.004])


class Material(Section):
    model: Literal[tuple(materials.MATERIALS)] = Field(  # type: ignore[valid-type]
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


class Physics(Section):
    gravity: list[float] = Field([0.0, -9.81], description="Gravitational acceleration (m/s^2); "
                                 "the default points down the last axis, [0, 0, -9.81] in 3D.",
                                 min_length=2, max_length=3)


class Time(Section):
    dt: Literal["auto"] | float = Field(
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


class Output(Section):
    interval: float = Field(
        0.01, gt=0, description="Simulated time between rows of timeseries.csv (s). The steps "
        "between two output times are all equal and at most time.dt, so every output time is "
        "landed on exactly.")
    snapshot_interval: float | None = Field(
        None, gt=0, description="Simulated time between particle snapshots (s); defaults to "
        "output.interval. Snapshots are written at the first output time at or after each "
        "multiple (so an interval shorter than output.interval means every output).")
    snapshots: bool = Field(True, description="Write particle snapshots (VTU files and a "
                            "particles.pvd time series for ParaView).")


class Checkpoint(Section):
    interval: float = Field(
        0.1, gt=0, description="Simulated time between checkpoints (s), written at the first "
        "output time at or after each multiple (every output for an interval shorter than "
        "output.interval), at the end of the run and when it is interrupted (Ctrl-C, "
        "SIGTERM). A checkpoint (checkpoint_NNNNNNNNN.npz in the output "
        "folder, the latest two kept) holds everything needed to continue: `mpmflow run CASE "
        "--out DIR --restart` resumes from the latest and reproduces the uninterrupted run "
        "bit for bit.")


class ProbeData(Section):
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


class Probe(Section):
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
    window: float | None = Field(
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
    data: ProbeData | None = Field(
        None, description="The measured series to compare with ([probes.data] table: path, "
        "column, time_column): `mpmflow plot` draws it beside the probe's.")


class Execution(Section):
    threads: Literal["auto"] | int = Field(
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


class Solver(Section):
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
    flip: float | None = Field(None, ge=0, le=1, description="FLIP fraction of the particle velocity "
                        "update per millisecond of simulated time: a step of dt blends FLIP and "
                        "PIC with the fraction flip^(dt / 1 ms), so the PIC damping per second "
                        "is the same whatever the time step and the scheme. 1 = pure FLIP "
                        "(the paper), 0 = pure PIC. The default keeps 1% PIC per millisecond, "
                        "which stops the thin surge tip from running ahead on FLIP noise. "
                        "Not used with solver.transfer = \"apic\".")
    transfer: Literal["flip", "apic"] = Field(
        "flip", description="Particle-grid velocity transfer of the projection scheme: "
        "\"flip\" = the FLIP/PIC blend set by solver.flip (the paper's FLIP with the "
        "default's 1% PIC per millisecond); \"apic\" = the affine particle-in-cell method "
        "(Jiang et al. 2015): each particle carries the velocity gradient of the corrected "
        "grid velocity at its position (a D x D matrix, kept in checkpoints) besides the PIC "
        "velocity, and gives the grid its affine velocity field, so the transfers keep "
        "rotation and shear that PIC damps (angular momentum is conserved by the transfers) "
        "without FLIP's particle noise; solver.flip is not used. The explicit scheme takes "
        "\"flip\" only. See docs/method.md, \"Transfers\".")
    full_cell_threshold: float = Field(
        0.9, gt=0, le=1, description="Cells with volume fraction theta at or above this are full "
        "and integrated with 2x2 Gauss points (paper: 0.9).")
    sparse_cell_threshold: float | None = Field(
        None, gt=0, lt=1, description="Cells with theta below this are left out of the "
        "pressure system (paper: 0.2). With free_surface = \"subcell\" the surface is placed "
        "by the nodal volume fraction, not by this threshold, and a low threshold keeps the "
        "few particles above a surface that lies on a grid line inside the system (left out, "
        "they fall freely until they rejoin it, which stirs the surface).")
    partial_cell_quadrature: Literal["gauss", "particles"] | None = Field(
        None, description="Quadrature of partial cells (sparse <= theta < full): "
        "\"particles\" integrates with the material points (the paper); \"gauss\" with Gauss "
        "points over the whole cell, consistent with free_surface = \"subcell\".")
    surface_quadrature: Literal["divergence", "consistent", "gauss"] | None = Field(
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
    free_surface: Literal["subcell", "node"] | None = Field(
        None, description="Free-surface condition: \"node\" sets p = 0 at nodes bordering "
        "left-out cells (the paper); \"subcell\" places p = 0 at the f = 1/2 level of the nodal "
        "volume fraction with ghost-fluid extrapolation.")
    wall_flux: bool | None = Field(
        None, description="Use the wall term of the weak form (grad p . n = rho/dt v*.n on "
        "wetted walls) with the divergence of the unconstrained v*. false = the paper's "
        "homogeneous Neumann condition with the wall-constrained v*.")
    ghost_theta_min: float = Field(
        0.01, gt=0, le=1, description="Smallest fractional distance from an unknown node to the "
        "free surface used in the ghost extrapolation (subcell only); keeps the system well "
        "conditioned when the surface passes very close to a node.")
    volume_correction: float | None = Field(
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
    density_correction: float | None = Field(
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
