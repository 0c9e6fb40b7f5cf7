"""The case's [solver] table: the scheme, the formulation of the pressure step (the paper's
or the project's default) and each of its choices, the solvers' tolerances (SI units)."""

from collections.abc import Callable
from typing import Any, Literal

from pydantic import Field, PrivateAttr, model_validator
from typing_extensions import Self

from .sections import Section

FORMULATIONS = {
    "mpmflow": {
        "free_surface": "subcell",
        "wall_flux": True,
        "partial_cell_quadrature": "gauss",
        "surface_quadrature": "divergence",
        "sparse_cell_threshold": 0.01,
        "volume_correction": 0.5,
        "density_correction": 0.0,
        "flip": 0.99,
    },
    "paper": {
        "free_surface": "node",
        "wall_flux": False,
        "partial_cell_quadrature": "particles",
        "surface_quadrature": "gauss",
        "sparse_cell_threshold": 0.2,
        "volume_correction": 0.0,
        "density_correction": 0.0,
        "flip": 1.0,
    },
}


class Solver(Section):
    scheme: Literal["projection", "explicit"] = Field(
        "projection",
        description='Time integration scheme: "projection" is the implicit '
        'Chorin projection of Kularathna & Soga (2017); "explicit" is the explicit weakly '
        "compressible MPM the paper compares with (update stress last, p = -K * volumetric "
        "strain once per cell; material.bulk_modulus; time step limited by the sound speed).",
    )
    formulation: Literal["mpmflow", "paper"] = Field(
        "mpmflow",
        description="Preset for free_surface, wall_flux, partial_cell_quadrature, "
        "surface_quadrature, sparse_cell_threshold, volume_correction, density_correction and "
        'flip: "paper" is '
        "the plain reading of Kularathna & Soga (2017) (p = 0 at free-surface nodes, "
        "homogeneous Neumann walls, material-point quadrature in partial cells, cells below "
        "theta = 0.2 left out, no correction of the particles' volume, pure FLIP); "
        '"mpmflow" is the default, which keeps a column at rest exactly at rest and the '
        "material at its volume. Keys set explicitly override the preset.",
    )
    flip: float | None = Field(
        None,
        ge=0,
        le=1,
        description="FLIP fraction of the particle velocity "
        "update per millisecond of simulated time: a step of dt blends FLIP and "
        "PIC with the fraction flip^(dt / 1 ms), so the PIC damping per second "
        "is the same whatever the time step and the scheme. 1 = pure FLIP "
        "(the paper), 0 = pure PIC. The default keeps 1% PIC per millisecond, "
        "which stops the thin surge tip from running ahead on FLIP noise. "
        'Not used with solver.transfer = "apic".',
    )
    transfer: Literal["flip", "apic"] = Field(
        "flip",
        description="Particle-grid velocity transfer of the projection scheme: "
        '"flip" = the FLIP/PIC blend set by solver.flip (the paper\'s FLIP with the '
        'default\'s 1% PIC per millisecond); "apic" = the affine particle-in-cell method '
        "(Jiang et al. 2015): each particle carries the velocity gradient of the corrected "
        "grid velocity at its position (a D x D matrix, kept in checkpoints) besides the PIC "
        "velocity, and gives the grid its affine velocity field, so the transfers keep "
        "rotation and shear that PIC damps (angular momentum is conserved by the transfers) "
        "without FLIP's particle noise; solver.flip is not used. The explicit scheme takes "
        '"flip" only. See docs/method.md, "Transfers".',
    )
    full_cell_threshold: float = Field(
        0.9,
        gt=0,
        le=1,
        description="Cells with volume fraction theta at or above this are full "
        "and integrated with 2x2 Gauss points (paper: 0.9).",
    )
    sparse_cell_threshold: float | None = Field(
        None,
        gt=0,
        lt=1,
        description="Cells with theta below this are left out of the "
        'pressure system (paper: 0.2). With free_surface = "subcell" the surface is placed '
        "by the nodal volume fraction, not by this threshold, and a low threshold keeps the "
        "few particles above a surface that lies on a grid line inside the system (left out, "
        "they fall freely until they rejoin it, which stirs the surface).",
    )
    partial_cell_quadrature: Literal["gauss", "particles"] | None = Field(
        None,
        description="Quadrature of partial cells (sparse <= theta < full): "
        '"particles" integrates with the material points (the paper); "gauss" with Gauss '
        'points over the whole cell, consistent with free_surface = "subcell".',
    )
    surface_quadrature: Literal["divergence", "consistent", "gauss"] | None = Field(
        None,
        description='With partial_cell_quadrature = "gauss": how the cells the free '
        "surface passes through are integrated besides the Laplacian (Gauss points). "
        '"divergence": the divergence of the predicted velocity (eq. 15) over the cell\'s '
        "material points, because the grid velocity in the air part of the cell is an "
        "extrapolation no equation constrains and its divergence, over the whole cell, does "
        "work against the extrapolated pressure (a standing wave gained energy); "
        '"consistent": the corrector\'s gradient and volumes too, so that the projection '
        "only takes energy out (at 0.01 m a standing wave then loses 1.8% per period and "
        'the coarse surge front is 0.007 a slower); "gauss": Gauss points over the whole '
        'cell for all (the earlier default). See docs/method.md, "Energy".',
    )
    free_surface: Literal["subcell", "node"] | None = Field(
        None,
        description='Free-surface condition: "node" sets p = 0 at nodes bordering '
        'left-out cells (the paper); "subcell" places p = 0 at the f = 1/2 level of the nodal '
        "volume fraction with ghost-fluid extrapolation.",
    )
    wall_flux: bool | None = Field(
        None,
        description="Use the wall term of the weak form (grad p . n = rho/dt v*.n on "
        "wetted walls) with the divergence of the unconstrained v*. false = the paper's "
        "homogeneous Neumann condition with the wall-constrained v*.",
    )
    ghost_theta_min: float = Field(
        0.01,
        gt=0,
        le=1,
        description="Smallest fractional distance from an unknown node to the "
        "free surface used in the ghost extrapolation (subcell only); keeps the system well "
        "conditioned when the surface passes very close to a node.",
    )
    shallow_fraction: float | Literal["auto"] = Field(
        "auto",
        description="Sub-cell surface only: a node with f > 1/2 nearer the free surface "
        "than this fraction of its edge to the air is not a pressure unknown; its pressure is "
        "interpolated between the unknowns behind it and p = 0 at the surface. This bounds the "
        "ghost extrapolation's weights by 1/shallow_fraction - 1 (up to 99 without) and keeps "
        "steps down to 0.05 ms from gaining energy, but damps standing waves over long runs "
        '(docs/method.md, Energy). "auto": 0.3 at steps small for the grid (water falling '
        "the tank crosses under 0.1 cells a step), 0 at larger ones; 0: never.",
    )
    volume_correction: float | None = Field(
        None,
        ge=0,
        le=1,
        description="Volume correction rate beta (dimensionless, per step): "
        "the particles' volume fraction on the cell grid is brought back towards 1 by moving "
        "the particles (never their velocity) along -grad q, -lap q = volume fraction - 1 on "
        "the cells holding material (q = 0 in empty cells, no flux through walls; within one "
        "cell of the free surface only an excess counts). It closes gaps and undoes packing, "
        "removing the fraction beta of the volume error each step. 0 = off (the paper).",
    )
    volume_correction_interval: float = Field(
        2e-3,
        gt=0,
        description="Simulated time between volume corrections (s): the "
        "correction runs every round(interval / time.dt) steps, every step when time.dt is "
        "this long or longer, removing the fraction volume_correction of the volume error "
        "each time. A correction costs about a fifth of a step; at time.dt = 1 ms, every "
        "second step halves that with the same volume, dam-break accuracy and sloshing "
        "energy (docs/method.md).",
    )
    volume_correction_tolerance: float = Field(
        1e-8,
        gt=0,
        lt=1,
        description="Relative residual the volume correction's linear solve must reach "
        "(the run stops if it does not). It moves particles by a fraction of a volume "
        "error, which the next correction takes up again, so it can be looser than the "
        "pressure's: on the 3D dam break at 0.004 m, 24 multigrid iterations a correction "
        "at 1e-8, 15 at 1e-4, the front and height at 0.1 s the same to 1 mm. At 1e-2 a "
        "run's flow depends on the solver (docs/notes/benchmarks-diary.md).",
    )
    density_correction: float | None = Field(
        None,
        ge=0,
        le=1,
        description="The earlier, velocity-based density correction beta "
        "(dimensionless): where the particles give a node more material volume than the node "
        "holds (vol_i > V_i), the projection asks for div v = beta (vol_i/V_i - 1)/dt. It only "
        "spreads packed particles and, under FLIP, adds kinetic energy (the water loosens and "
        "a standing wave grows): kept for comparison, off by default; use "
        "solver.volume_correction instead.",
    )
    linear_solver: Literal["multigrid", "amg", "direct", "petsc"] = Field(
        "multigrid",
        description='Pressure solver: "multigrid" = conjugate gradients '
        'preconditioned by geometric multigrid on the grid (compiled); "amg" = conjugate '
        'gradients with smoothed-aggregation algebraic multigrid (pyamg); "direct" = sparse '
        'LU (SciPy); "petsc" = PETSc\'s conjugate gradients with the preconditioner '
        "solver.petsc_preconditioner, its rows split over the MPI processes of the run "
        "(needs the MPI environment: make setup-mpi).",
    )
    petsc_preconditioner: Literal["gamg", "hypre"] = Field(
        "hypre",
        description="The preconditioner of PETSc's conjugate gradients (runs on several MPI "
        'ranks, and solver.linear_solver = "petsc"): "hypre" = hypre\'s BoomerAMG (the '
        "default: on the dam break half the iterations and a third less time a step than "
        'GAMG, docs/notes/benchmarks-diary.md), "gamg" = PETSc\'s smoothed-aggregation algebraic '
        "multigrid (for a PETSc built without hypre). PETSc's options reach the pressure "
        "solve under the prefix mpmflow_pressure_ (PETSC_OPTIONS).",
    )
    tolerance: float = Field(
        1e-8,
        gt=0,
        lt=1,
        description="Relative residual every linear solve of a step must reach (the "
        "pressure, the viscous predictor, the volume correction); the run stops if one "
        "does not.",
    )
    max_iterations: int = Field(
        200, ge=1, le=100000, description="Iteration limit of the pressure solve."
    )
    max_speed: float = Field(
        100.0,
        gt=0,
        description="Largest particle speed (m/s) the run accepts: a faster "
        "particle means the computation is blowing up, and the run stops with the step, time "
        "and particle (exit code 3), keeping the outputs written so far. Checked after every "
        "output interval (the explicit scheme: every step). The default, 100 m/s, is about "
        "ten times the speed of water falling 5 m; raise it for faster flows.",
    )
    pressure_smoothing: Literal["nodal", "none"] = Field(
        "nodal",
        description="Explicit scheme: the pressure is evaluated once per cell from "
        "the volumetric strain of the particles in it, and that cell pressure drives the "
        'motion. The particles report it smoothed with "nodal" (each node takes the '
        "volume-weighted average of the cells around it, interpolated to the particle) or "
        'as their cell\'s value with "none".',
    )

    explicit_mass_cutoff: float = Field(
        0.0,
        ge=0,
        lt=1,
        description="Explicit scheme: a node whose mass is below this "
        "fraction of a full node's (density * grid.spacing^2 per unit depth) takes gravity "
        "only, no internal force, so that nearly empty nodes do not receive huge "
        "accelerations (0 = every node with mass).",
    )
    explicit_bulk_viscosity: list[float] = Field(
        [0.06, 1.5],
        min_length=2,
        max_length=2,
        description="Explicit scheme: artificial "
        "bulk viscosity [linear, quadratic] (dimensionless), as in explicit hydrocodes: a "
        "compressing cell (div v = D < 0) adds q = rho (linear c h |D| + quadratic h^2 D^2) to "
        'its pressure (c the sound speed, h the grid spacing); with time.dt = "auto" the '
        "step is then at most h / (|v| + Q + sqrt(Q^2 + c^2)), Q = linear c + quadratic h |D| "
        "of the most compressing cell. The default, the hydrocodes' usual [0.06, 1.5], carries "
        "the K = 2.2 GPa dam break at 0.004 m through the wall impact, where without it a "
        "particle of the jet up the wall reached 124 m/s at 0.248 s; [0, 0] = none.",
    )
    explicit_cell_threshold: float = Field(
        0.1,
        ge=0,
        lt=1,
        description="Explicit scheme: a cell whose particles' reference "
        "volume fills less than this fraction of it is too empty to define a volumetric "
        "strain: it holds no pressure and its particles keep their reference volume "
        "(0 = every cell with a particle). The default, 0.1, leaves out a cell holding a "
        "single particle of the usual 16 (1/16 of the cell): without it, at K = 2.2 GPa, "
        "splashes of lone particles reached 100-500 m/s and stopped the dam break at 0.31 s.",
    )
    explicit_tension: float = Field(
        0.0,
        ge=0,
        description="Explicit scheme: the largest tension (Pa) the material holds, "
        "p >= -explicit_tension (0 = none: free water holds no tension).",
    )

    _from_preset: set[str] = PrivateAttr(default_factory=set)  # keys the preset gave

    @model_validator(mode="after")
    def _shallow_fraction(self) -> Self:
        x = self.shallow_fraction
        if x != "auto" and not 0.0 <= x < 1.0:
            raise ValueError(
                f'solver.shallow_fraction = {x:g} is not "auto" or a fraction of an edge from '
                "0 (no shallow nodes) to below 1"
            )
        return self

    @model_validator(mode="wrap")
    @classmethod
    def _preset(cls, data: Any, handler: Callable[[Any], "Solver"]) -> "Solver":
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

    def __setattr__(self, name: str, value: Any) -> None:
        """Assigning formulation after loading applies its preset to the keys the preset
        gave (not those set explicitly), as --set solver.formulation=... does."""
        super().__setattr__(name, value)
        if name == "formulation":
            for key in sorted(self._from_preset):
                super().__setattr__(key, FORMULATIONS[value][key])
        elif name in FORMULATIONS["mpmflow"]:
            self._from_preset.discard(name)

    @model_validator(mode="after")
    def _given(self) -> Self:
        # the keys a formulation presets are None only until the preset fills them: None
        # given for one (in Python) is not a value
        for key in FORMULATIONS["mpmflow"]:
            if getattr(self, key) is None:
                raise ValueError(
                    f"solver.{key} = None is not a value; give one, or leave the key out for "
                    f"the formulation's ({self.formulation}) default"
                )
        return self

    @model_validator(mode="after")
    def _thresholds(self) -> Self:
        sparse = self.sparse_cell_threshold  # set by the formulation's preset
        if sparse is not None and sparse >= self.full_cell_threshold:
            raise ValueError(
                "solver.sparse_cell_threshold must be smaller than solver.full_cell_threshold"
            )
        return self
