"""The whole case (``Case``): its sections and the rules between them (bodies inside the
domain and apart, time step against end, probes inside, ...), checked as one."""

import math
from pathlib import Path

import numpy as np
from pydantic import Field, PrivateAttr, ValidationInfo, model_validator
from typing_extensions import Self

from .. import materials
from ..geometry import bodies, placement
from ..geometry.shapes import DIM_OF, Shape
from ..geometry.specs import from_spec
from ..grid import Grid
from ..materials import poroelastic
from ..stability import case_stable_time_step, initial_speed, sound_speed, time_step
from . import capabilities, probe_data
from .domain import Domain
from .inlets import Inlet
from .inlets import problem as inlet_problem
from .loads import Load, Plate, plate_problem
from .loads import problem as load_problem
from .sections import (
    MAX_PRESSURE,
    MAX_STEPS,
    Checkpoint,
    Execution,
    GridSettings,
    Material,
    Output,
    Physics,
    Probe,
    Section,
    Time,
)
from .shapes import Body, Obstacle
from .shapes import Box as BoxBody
from .solver import Solver
from .sponges import Sponge
from .sponges import problem as sponge_problem

# A periodic axis is halved by the multigrid while its period stays a multiple of 4
# (src/core/multigrid.cpp); the points left on the coarsest level enter a dense solve at
# every step (with the other axes' 2 or 3 points: at most a few hundred unknowns).
MAX_COARSEST_PERIOD = 64


def _coarsest_period(cells: int) -> int:
    """The points a periodic axis of ``cells`` cells keeps on the coarsest level."""
    while cells % 4 == 0 and cells >= 8:
        cells //= 2
    return cells


class Case(Section):
    title: str = Field("", description="Free text shown in outputs.")
    domain: Domain
    grid: GridSettings
    bodies: list[Body] = Field(
        description="Bodies of material ([[bodies]] tables), each of a shape (bodies.N.type).",
        min_length=1,
    )
    obstacles: list[Obstacle] = Field(
        [],
        description="Fixed rigid obstacles ([[obstacles]] tables): structures the "
        "material flows round, of the same shapes and shape keys as bodies (obstacles.N.type; "
        "at least two grid cells thick). Bodies may surround them: the lattice points inside "
        "an obstacle are not seeded.",
    )
    material: Material = Material()
    physics: Physics = Physics()
    time: Time
    output: Output = Output()
    solver: Solver = Solver()
    checkpoint: Checkpoint = Checkpoint()
    probes: list[Probe] = Field(
        [],
        description="Probes ([[probes]] tables): pressure sensors and water-level gauges "
        "sampled at every output time into probes.csv (a column per probe, named by "
        "probes.N.name; time in s).",
    )
    inlets: list[Inlet] = Field(
        [],
        description="Velocity inlets ([[inlets]] tables): water entering through part of a "
        "side at a given speed (inlets.N.side, speed, level), so that a channel with an "
        "outlet downstream runs steady; what entered is counted in summary.json's inflow. "
        "The projection scheme only, one process.",
    )
    sponges: list[Sponge] = Field(
        [],
        description="Damping zones along the domain's sides ([[sponges]] tables: "
        "sponges.N.side, length, strength): a numerical beach where the water's velocity is "
        "relaxed towards rest, so that waves and what a body radiates leave instead of "
        "reflecting from the walls. The projection scheme only, one process.",
    )
    loads: list[Load] = Field(
        [],
        description="Surface loads ([[loads]] tables: loads.N.axis, at, lower, upper, "
        "traction): a traction (Pa) on a face of the material at a plane of the grid's nodes, "
        "as a consolidation test's load on a column's top. The projection scheme only, one "
        "process.",
    )
    plate: Plate | None = Field(
        None,
        description="A rigid plate on a wall ([plate]: plate.side, force): frictionless and "
        "impermeable, pressed on a saturated soil with a constant total force, its velocity "
        "what makes the soil's reaction meet the force (Mandel's problem). One process.",
    )
    execution: Execution = Execution()

    _base_dir: Path | None = PrivateAttr(None)  # the case file's folder
    _shapes: dict[tuple[str, int, str, str], Shape] = PrivateAttr(
        default_factory=dict
    )  # built shapes, by their tables
    _counts: dict[tuple[str, str], list[float]] = PrivateAttr(
        default_factory=dict
    )  # particle counts, by the geometry

    def __eq__(self, other: object) -> bool:
        """Equal cases: the same settings and folder (the caches of shapes and counts
        aside)."""
        if not isinstance(other, Case):
            return NotImplemented
        return self.__dict__ == other.__dict__ and self._base_dir == other._base_dir

    @property
    def base_dir(self) -> Path:
        """The folder relative paths of the case (mesh files) start from: the case file's,
        or the current folder for a case not read from a file."""
        return self._base_dir if self._base_dir is not None else Path.cwd()

    def _shape(self, kind: str, k: int) -> Shape:
        spec = getattr(self, kind)[k]
        key = (kind, k, repr(spec.model_dump()), str(self.base_dir))  # (not JSON: a path
        # that is not UTF-8 has no JSON text)
        if key not in self._shapes:
            self._shapes[key] = from_spec(
                spec, len(self.domain.size), self.base_dir, key=f"{kind}.{k}"
            )
        return self._shapes[key]

    def _free_water_problem(self) -> str | None:
        """Free water (bodies.N.free_water) is a saturated soil's; a geostatic start needs
        gravity down the last axis."""
        saturated = self.material.model in materials.SATURATED
        for k, body in enumerate(self.bodies):
            if body.free_water and not saturated:
                return (
                    f"bodies.{k}.free_water = true is the free water beside a saturated soil "
                    f'(material.model = "poroelastic"), not of material.model = '
                    f"{self.material.model!r}: remove it (the whole case's material is "
                    "the body's)"
                )
        if saturated and self.material.initial_stress == "geostatic":
            return poroelastic.geostatic_problem(self.physics.gravity)
        return None

    def _unsupported(self) -> str | None:
        """The message for a feature the case uses that its scheme does not support (each
        scheme's, ``capabilities.SUPPORTS``); None when there is none."""
        used = {
            "obstacles": (bool(self.obstacles), "remove the [[obstacles]]"),
            "materials": (self.material.model != "water", 'set material.model = "water"'),
            "periodic": (any(self.domain.periodic or []), "remove domain.periodic"),
            "apic": (self.solver.transfer == "apic", 'set solver.transfer = "flip"'),
            "outlets": (
                any(self.domain.outlet_sides()),
                'make the outlet sides of domain.walls "slip"',
            ),
            "solids": (
                materials.is_solid(self.material),
                'give a fluid material.model ("water", "newtonian", ...)',
            ),
            "bonded": (
                any(self.domain.bonded_sides()),
                'make the bonded sides of domain.walls "no_slip"',
            ),
            "inlets": (bool(self.inlets), "remove the [[inlets]]"),
            "sponges": (bool(self.sponges), "remove the [[sponges]]"),
            "loads": (bool(self.loads), "remove the [[loads]]"),
        }
        name = self.solver.scheme
        for feature, (uses, instead) in used.items():
            if uses and not capabilities.supports(name, feature):
                others = " or ".join(f'"{n}"' for n in capabilities.supporting(feature))
                return (
                    f'solver.scheme = "{name}" does not support '
                    f"{capabilities.FEATURES[feature]}; set solver.scheme = {others}, or "
                    f"{instead}"
                )
        return None

    def _periodic_problem(self, size: list[float], obstacle_shapes: list[Shape]) -> str | None:
        """What is wrong with domain.periodic for this case (None: nothing)."""
        periodic = self.domain.periodic or []
        if not any(periodic):
            return None
        axes = "xyz"
        h = self.grid.spacing
        coarsest = 1
        for k, flag in enumerate(periodic):
            if not flag:
                continue
            n = size[k] / h
            whole = round(n)
            if abs(n - whole) > 1e-6 * n or whole % 2 or whole < 4:
                even = max(4, 2 * round(n / 2))
                return (
                    f"domain.periodic: along {axes[k]} domain.size = {size[k]:g} m is "
                    f"{n:.6g} cells of grid.spacing = {h:g} m; a periodic axis needs a "
                    f"whole, even number of cells, at least 4: make domain.size[{k}] = "
                    f"{even * h:.6g} m ({even} cells) or change grid.spacing"
                )
            unit = np.zeros(len(size))
            unit[k] = 1.0
            left = _coarsest_period(whole)
            coarsest *= left
            if coarsest > MAX_COARSEST_PERIOD:
                better = max(8, round(whole / 8) * 8)
                return (
                    f"domain.periodic: along {axes[k]} the {whole} cells halve down to "
                    f"no fewer than {left} points on the pressure solver's coarsest level "
                    "(a periodic axis halves while its period stays a multiple of 4), "
                    f"{coarsest} with the other periodic axes, too many for its dense "
                    f"solve at every step; make domain.size[{k}] a multiple of 8 cells, "
                    f"e.g. {better * h:.6g} m ({better} cells)"
                )
            for j, shape in enumerate(obstacle_shapes):
                lo, hi = -shape.support(-unit), shape.support(unit)
                if lo < h or hi > size[k] - h:
                    return (
                        f"obstacles.{j} spans {lo:.6g} to {hi:.6g} m along the periodic "
                        f"axis {axes[k]} of [0, {size[k]:g}] m; an obstacle must stay a "
                        f"grid cell ({h:g} m) inside a periodic axis's ends: move or "
                        "shrink it, or make the axis a wall (domain.periodic)"
                    )
        return None

    def body_shape(self, k: int) -> Shape:
        """The ``geometry.shapes`` shape of bodies.k."""
        return self._shape("bodies", k)

    def obstacle_shape(self, k: int) -> Shape:
        """The ``geometry.shapes`` shape of obstacles.k."""
        return self._shape("obstacles", k)

    def particle_counts(self) -> list[float]:
        """The exact number of particles each body is seeded with (obstacles left out)."""
        key = (
            repr(self.model_dump(include={"bodies", "obstacles", "grid", "domain"})),
            str(self.base_dir),
        )
        if key not in self._counts:
            obstacles = [self.obstacle_shape(j) for j in range(len(self.obstacles))]
            self._counts[key] = [
                bodies.particle_count(b, self.grid.spacing, self.body_shape(k), obstacles)
                for k, b in enumerate(self.bodies)
            ]
        return self._counts[key]

    def _same_dimension(self) -> None:
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
                if D not in DIM_OF[spec.type]:
                    other = [t for t, d in DIM_OF.items() if D in d]
                    raise ValueError(
                        f"{kind}.{k}.type = {spec.type!r} is a shape of "
                        f"{DIM_OF[spec.type][0]}D cases, but domain.size = "
                        f"{self.domain.size} makes this case {D}D; give {kind}.{k} one of the "
                        f"{D}D shapes ({', '.join(repr(t) for t in other)})"
                    )
                vectors += [
                    (f"{kind}.{k}.{name}", getattr(spec, name))
                    for name in spec.VECTORS
                    if name != "translate" and name != "axis"
                ]
        for k, body in enumerate(self.bodies):
            vectors.append((f"bodies.{k}.velocity", body.velocity))
        for k, spec in enumerate(self.obstacles):
            motion = getattr(spec, "motion", None)
            if motion is None:
                continue
            if motion.pivot is not None:
                vectors.append((f"obstacles.{k}.motion.pivot", motion.pivot))
            for name in ("velocity", "amplitude"):
                value = getattr(motion, name)
                if value is not None and len(value) != D:
                    vectors.append((f"obstacles.{k}.motion.{name}", value))
        vectors += [(f"probes.{k}.position", p.position) for k, p in enumerate(self.probes)]
        for name, value in vectors:
            if len(value) != D:
                raise ValueError(
                    f"{name} = {value} has {len(value)} entries but domain.size = "
                    f"{self.domain.size} has {D}: a {D}D case needs {D} entries in every "
                    f"vector; give {name} {D} entries, or domain.size {len(value)}"
                )
        if D == 3:
            for k, body in enumerate(self.bodies):
                if isinstance(body, BoxBody) and body.surface_amplitude:
                    raise ValueError(
                        f"bodies.{k}.surface_amplitude = {body.surface_amplitude:g} m: the "
                        "cosine top surface is defined for 2D cases only so far; use a flat "
                        "box in 3D (surface_amplitude = 0)"
                    )

    def _pressure_scale(self, size: list[float]) -> None:
        """The hydrostatic pressure over the domain's height, rho |g| H, below MAX_PRESSURE:
        density and gravity within their ranges can still make it meaningless in a domain
        of absurd size (the pressure solve's sums of squares overflow near 1e150 Pa)."""
        g = math.hypot(*self.physics.gravity)
        if g == 0:
            return
        height = sum(abs(c) / g * s for c, s in zip(self.physics.gravity, size))
        scale = self.material.density * g * height
        if not scale <= MAX_PRESSURE:
            raise ValueError(
                f"the hydrostatic pressure over the domain's height, material.density x "
                f"|physics.gravity| x {height:.4g} m = {scale:.3g} Pa, is above "
                f"{MAX_PRESSURE:g} Pa, where no liquid or granular material is "
                "incompressible (water's bulk modulus is 2.2e9 Pa): a mistake of units? Give "
                "domain.size in m, material.density in kg/m^3 and physics.gravity in m/s^2"
            )

    @model_validator(mode="after")
    def _consistent(self, info: ValidationInfo) -> Self:
        if info.context and info.context.get("base_dir") is not None:
            self._base_dir = Path(info.context["base_dir"])
        size = self.domain.size
        self._same_dimension()
        message = (
            self._unsupported()
            or inlet_problem(self)
            or sponge_problem(self)
            or load_problem(self)
            or plate_problem(self)
            or self._free_water_problem()
        )
        if message:
            raise ValueError(message)
        if self.domain.uniform_walls() is None:
            for k, obstacle in enumerate(self.obstacles):
                if obstacle.walls == "domain":
                    raise ValueError(
                        f'obstacles.{k}.walls = "domain" (the default) takes the condition '
                        "of domain.walls, but domain.walls gives its walls different ones "
                        f'({self.domain.walls_text()}); set obstacles.{k}.walls = "slip" or '
                        '"no_slip"'
                    )
        folder = (info.context or {}).get("folder") if info is not None else None
        for k, probe in enumerate(self.probes):
            if probe.data is not None:
                probe_data.check(k, probe.data, folder)
        if any(s < 2 * self.grid.spacing * (1 - 1e-9) for s in size):
            raise ValueError(
                f"grid.spacing = {self.grid.spacing:g} m is larger than half the domain "
                f"({size} m); the grid needs at least two cells per side"
            )
        most = max(s / self.grid.spacing for s in size)
        if not np.isfinite(most):  # a huge finite count is the memory check's to refuse
            raise ValueError(
                f"grid.spacing = {self.grid.spacing:g} m makes {most:.3g} cells along a side "
                f"of the domain ({size} m), beyond what any computer holds; give a larger "
                "grid.spacing (the paper's dam break uses 0.004 m)"
            )
        # (a density of at least MIN_DENSITY keeps the particles' mass above underflow
        # wherever their volume is: a volume that underflows is the memory check's)
        self._pressure_scale(size)
        for k, body in enumerate(self.bodies):
            if not isinstance(body, BoxBody):
                continue  # placement.check
            crest = body.max[1] + abs(body.surface_amplitude)
            if body.surface_amplitude and crest > size[1] * (1 + 1e-12):
                raise ValueError(
                    f"bodies.{k}: the cosine surface reaches max[1] + |surface_amplitude| = "
                    f"{crest:g} m, above the domain's top at {size[1]:g} m; lower "
                    f"bodies.{k}.max or surface_amplitude, or enlarge domain.size"
                )
            for lo, hi, s in zip(body.min, body.max, size):
                if lo < -1e-12 or hi > s * (1 + 1e-12):
                    box = " x ".join(f"[0, {s:g}]" for s in size)
                    raise ValueError(
                        f"bodies.{k} spans {body.min} to {body.max} m, outside the domain "
                        f"{box} m; move it inside (bodies.{k}.min/max) or enlarge domain.size"
                    )
        overlap = bodies.overlap_message(self.bodies, self.grid.spacing)
        if overlap:
            raise ValueError(overlap)
        body_shapes = [self.body_shape(k) for k in range(len(self.bodies))]
        obstacle_shapes = [self.obstacle_shape(k) for k in range(len(self.obstacles))]
        placement.check(self, body_shapes, obstacle_shapes)
        if obstacle_shapes:
            for k, count in enumerate(self.particle_counts()):
                message = (
                    placement.empty_body_message(self, k, body_shapes[k], obstacle_shapes)
                    if count == 0
                    else None
                )
                if message:
                    raise ValueError(message)
                if not self.bodies[k].around_obstacles:
                    message = placement.overlap_message(
                        self, k, count, body_shapes[k], obstacle_shapes
                    )
                    if message:
                        raise ValueError(message)
        if self.solver.scheme == "projection":
            grid = Grid.covering(size, self.grid.spacing)
            if bodies.fills_grid(self.bodies, self.grid.spacing, grid.size):
                used = " x ".join(f"{s:.6g}" for s in grid.size)
                raise ValueError(
                    f"the bodies fill the whole domain ({used} m on the grid), leaving no "
                    "free surface: the projection scheme's incompressible material then has "
                    "no pressure level (the pressure system is singular). Leave empty space "
                    "above the material, at least one grid cell: lower the top of the bodies "
                    "(bodies.N.max) or enlarge domain.size"
                )
        message = self._periodic_problem(size, obstacle_shapes)
        if message:
            raise ValueError(message)
        names = set()
        for k, probe in enumerate(self.probes):
            if probe.name in names:
                raise ValueError(
                    f"probes.{k}.name = {probe.name!r} is the name of an earlier "
                    "probe; give each probe its own name (its column in "
                    "probes.csv)"
                )
            names.add(probe.name)
            if any(not 0 <= p <= s * (1 + 1e-12) for p, s in zip(probe.position, size)):
                box = " x ".join(f"[0, {s:g}]" for s in size)
                raise ValueError(
                    f"probes.{k}.position = {probe.position} m lies outside the "
                    f"domain {box} m; move it inside"
                )
            spacing = min(self.grid.spacing / b.particles_per_cell for b in self.bodies)
            if probe.quantity == "pressure" and probe.window is not None:
                if probe.window < spacing * (1 - 1e-9):
                    raise ValueError(
                        f"probes.{k}.window = {probe.window:g} m is narrower than the "
                        f"particles' spacing, {spacing:.4g} m (grid.spacing / particles_per_cell "
                        "of the densest body): it holds at most one particle at a time and none "
                        "most of the time, so the probe would read 0 (a dry sensor) in water; "
                        f"give a window of a few particle spacings (at least {spacing:.4g} m), "
                        "or none for the default (the fewest whole grid cells that hold the "
                        "particles of a fit)"
                    )
            if probe.window is not None and probe.window > max(size):
                raise ValueError(
                    f"probes.{k}.window = {probe.window:g} m is wider than the "
                    f"domain (largest side {max(size):g} m), so it would read "
                    "particles anywhere; give a window of a few grid cells "
                    f"(grid.spacing = {self.grid.spacing:g} m), or none for "
                    "the default"
                )
        for k, body in enumerate(self.bodies):
            speed = float(np.linalg.norm(body.velocity))
            if not speed <= self.solver.max_speed:
                raise ValueError(
                    f"bodies.{k}.velocity = {body.velocity} m/s is {speed:.4g} m/s fast, above "
                    f"solver.max_speed = {self.solver.max_speed:g} m/s, at which the run would "
                    f"stop at once; give a slower velocity or raise solver.max_speed"
                )
        dt = time_step(self)
        if self.time.end < dt * (1 - 1e-9):
            raise ValueError(
                f"time.end = {self.time.end:g} s is shorter than one time step of {dt:.3g} s "
                f"(time.dt = {self.time.dt!r}); a run takes at least one step: give a later "
                "time.end, or a smaller time.dt"
            )
        steps = self.time.end / dt
        if not steps <= MAX_STEPS:
            raise ValueError(
                f"time.end = {self.time.end:g} s is {steps:.3g} steps of {dt:.3g} s, more than "
                f"the {MAX_STEPS:,} a run can take (checkpoints are numbered by step with 9 "
                "digits; at a few milliseconds per step that many steps take weeks): give a "
                "shorter time.end, or a larger time.dt"
            )
        if self.time.dt != "auto" and self.solver.scheme == "explicit":
            limit = case_stable_time_step(self)
            if self.time.dt > limit:
                c = sound_speed(self.material.bulk_modulus, self.material.density)
                raise ValueError(
                    f"time.dt = {self.time.dt:g} s is above the stable step of the explicit "
                    f"scheme, {limit:.4g} s = grid.spacing / (sound speed + initial speed) = "
                    f"{self.grid.spacing:g} / ({c:.4g} + {initial_speed(self):.3g}) m/s; set "
                    f'time.dt to at most {limit:.4g} s, or time.dt = "auto" (which uses '
                    f"time.safety_factor = {self.time.safety_factor:g} of it), or lower "
                    "material.bulk_modulus"
                )
        saturated = self.material.model in materials.SATURATED
        if (self.time.dt == "auto" and saturated) or (
            self.time.dt != "auto"
            and materials.coupled_step(self.material, self.grid.spacing, self.time.dt)
        ):
            # past the solid's step the elastic solve and the projection are solved as one
            # system (State::coupled_solve), with the walls and the tools (obstacles on a
            # path) holding what the split step's contacts hold; not with fixed obstacles
            # (cut cells, not a solid's staircase) or damping zones (which act between the
            # two solves)
            fixed = [o for o in self.obstacles if getattr(o, "motion", None) is None]
            # nor with a pressure-dependent strength: the coupled step's plastic iterations
            # (State::plastic_solve) settle a Tresca clay's flow, but on a Drucker-Prager
            # column (examples/bui_column.toml at h = 5 mm and 5 times the step) they
            # stalled at a stress change of 2e-3 to 1e-2 of the largest (the tolerance
            # 1e-3) from 0.34 s on, under-relaxed from 0.17 s
            frictional = self.material.model in materials.FRICTIONAL
            held = [
                name
                for name, on in (
                    ("fixed obstacles", fixed),
                    ("sponges", self.sponges),
                    (
                        f"pressure-dependent strength (material.model = {self.material.model!r})",
                        frictional,
                    ),
                )
                if on
            ]
            if held and saturated:
                raise ValueError(
                    f"material.model = {self.material.model!r}: a saturated soil takes the "
                    "elastic solve and the projection as one system at every step, which takes "
                    f'no {" or ".join(held)} yet (docs/method.md, "Saturated soil"): remove '
                    "them"
                )
            if held:
                solid_step = materials.shear_wave_step(self.material, self.grid.spacing)
                c = (self.material.shear_modulus / self.material.density) ** 0.5
                raise ValueError(
                    f"time.dt = {self.time.dt:g} s is above a solid's step, {solid_step:.4g} s "
                    f"= {materials.SHEAR_COURANT:g} grid.spacing / sqrt(material.shear_modulus "
                    f"/ material.density) = {materials.SHEAR_COURANT:g} x {self.grid.spacing:g} "
                    f"m / {c:.4g} m/s, past which the elastic solve and the projection are "
                    f"solved together, which takes no {' or '.join(held)} yet "
                    f'(docs/method.md, "Solids"): set time.dt to at most {solid_step:.4g} s, '
                    'or time.dt = "auto", which takes it'
                )
        if self.time.dt != "auto" and self.output.interval < self.time.dt * (1 - 1e-9):
            raise ValueError(
                f"output.interval = {self.output.interval:g} s is shorter than time.dt = "
                f"{self.time.dt:g} s; make it at least one time step"
            )
        # once checked: mesh files by absolute path, so that the resolved case
        # (summary.json) finds them from anywhere (as probes' data)
        for spec in [*self.bodies, *self.obstacles]:
            if spec.type == "mesh" and not Path(spec.path).expanduser().is_absolute():
                path = (self.base_dir / Path(spec.path).expanduser()).resolve()
                if path.is_file():
                    object.__setattr__(spec, "path", str(path))
        return self
