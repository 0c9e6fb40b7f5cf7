"""What a run is made of, and the checks a case must pass to run here: the grid, the
particles and the scheme built from the case, its memory estimate, the time step, and the
notices the run's summary will carry."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

from .. import checkpoint, memory
from ..boundaries import obstacles
from ..case import Case
from ..diagnostics import parts
from ..errors import CaseError, SolverError
from ..geometry import mass
from ..geometry.seeding import build_particles
from ..grid import Grid
from ..materials import stiffness
from ..particles import Particles, subset
from ..schemes import Scheme, registry
from ..stability import time_step
from ..threads import setting_from

if TYPE_CHECKING:
    from .loop import Simulation


@dataclass
class Setup:
    memory: memory.Estimate
    files: dict[str, checkpoint.FileHash]  # the content hashes of the files the case reads
    grid: Grid
    particles: Particles
    scheme: Scheme
    dt: float
    notices: list[str]


def make_scheme(case: Case, grid: Grid, particles: Particles) -> Scheme:
    """The case's scheme; started on several MPI processes, its form over the ranks
    (``parallel.scheme``)."""
    from ..parallel.comm import launched_size

    if launched_size() > 1:
        from ..parallel.support import distributed

        return distributed(case, grid, particles)
    return registry()[case.solver.scheme](case, grid, particles)


def _check_memory(case: Case) -> memory.Estimate:
    """The memory estimate, checked against what this machine can give: one process's, or
    under mpirun each rank's (``parallel.memory``) for the ranks this machine holds."""
    from ..parallel.comm import launched_size

    if launched_size() == 1:
        return memory.check(case)
    from ..parallel import memory as per_rank

    estimate = memory.estimate(case)
    estimate.per_rank = per_rank.check(case, launched_size())
    return estimate


def build(case: Case) -> Setup:
    """The Setup of a validated ``case``; CaseError when it cannot run here."""
    setting_from(case.execution.threads)  # a bad MPMFLOW_THREADS is refused here
    estimate = _check_memory(case)
    try:  # each body's seeded mass against rho V: a body smaller than its particles is
        # refused, one a few percent off is told (the counts are the estimate's)
        notices = mass.check(case)
    except ValueError as err:
        raise CaseError(f"{err}.") from None
    # the content of the files the case reads, as this run reads them (checkpoints keep
    # it, and a restart with other files is refused)
    files = checkpoint.file_hashes(case)
    from ..parallel.comm import launched_size

    grid = Grid.of_case(case)
    comm, numbers = parts.ALONE, None  # one process: the whole run, in its order
    if launched_size() > 1:  # each rank seeds its own particles only (parallel.seeding)
        from ..parallel.comm import world
        from ..parallel.seeding import seed_part

        comm = world()
        particles, numbers = seed_part(case, grid, comm)
    else:
        particles = build_particles(case, grid)
    if parts.count(comm, particles.count) == 0:
        raise CaseError(
            "The bodies hold no particles: every body is thinner than one "
            "particle spacing (grid.spacing / bodies.N.particles_per_cell). "
            "Enlarge the bodies or raise particles_per_cell."
        )
    scheme = make_scheme(case, grid, particles)
    if numbers is not None:
        scheme.adopt(numbers)  # type: ignore[attr-defined]
    solids = getattr(scheme, "solids", None)
    if solids is not None:
        inside = obstacles.in_solid_cells(solids, grid, particles.x)
        left_out = parts.count(comm, int(inside.sum()))
        if left_out == parts.count(comm, particles.count):
            raise CaseError(
                "Every particle lies in the solid the grid sees: the bodies fill only the "
                "space that obstacles touching the walls close off on this grid. "
                f"Refine grid.spacing (now {case.grid.spacing:g} m) or move the bodies."
            )
        if left_out:
            if numbers is not None:  # the numbers in the run of those kept
                from ..parallel.seeding import renumbered

                numbers = renumbered(comm, numbers, inside)
            particles = subset(particles, ~inside)
            scheme.particles = particles
            if numbers is not None:
                scheme.adopt(numbers)  # type: ignore[attr-defined]
            notices.append(
                f"{left_out} particle{'s' if left_out > 1 else ''} seeded "
                "round an obstacle lie in the solid the grid sees, which differs from the "
                "obstacle's shape within a cell of its face (where an obstacle touches two or "
                "three walls the corner between it and the walls is closed within the first "
                "cell; under a disc, a sphere or an overhang the thin wedge of water against "
                "the wall is filled) and are left out; a finer grid.spacing narrows that band"
            )
    if hasattr(scheme, "check_free_surface"):
        try:
            scheme.check_free_surface()
        except SolverError:
            raise CaseError(
                "The material touches no free surface at the start: the bodies leave too "
                "little empty space in the domain (under about one grid cell next to the "
                "material), so the projection scheme's pressure has no level to refer to "
                "and its system is singular. Leave at least one grid cell of empty space "
                f"(grid.spacing = {case.grid.spacing:g} m) above the material: lower the "
                "top of the bodies (bodies.N.max) or enlarge domain.size."
            ) from None
    dt = time_step(case)
    try:  # a viscous material too stiff for the time step: refused, or told
        notices += stiffness.check(case, particles, dt, comm)
    except ValueError as err:
        raise CaseError(str(err)) from None
    # what reading the mesh files had to decide (a binary STL's wrong triangle count)
    for shape in [case.body_shape(k) for k in range(len(case.bodies))] + [
        case.obstacle_shape(k) for k in range(len(case.obstacles))
    ]:
        notices += getattr(shape, "notes", [])
    if grid.adjusted(case.domain.size):
        used = " x ".join(f"{s:.6g}" for s in grid.size)
        asked = " x ".join(f"{s:.6g}" for s in case.domain.size)
        notices.append(
            f"domain {asked} m is not a whole number of {case.grid.spacing:g} m cells; the "
            f"walls are placed on the grid at {used} m"
        )
    return Setup(estimate, files, grid, particles, scheme, dt, notices)


def describe(sim: Simulation) -> list[str]:
    """What runs, how many steps and outputs, and the memory estimate (lines of text)."""
    case, g, est = sim.case, sim.grid, sim.memory
    steps = max(1, round((case.time.end - sim.time) / sim.dt))
    cells = " x ".join(str(n) for n in g.cells)
    snaps = (
        f", a snapshot every {case.output.snapshot_interval or case.output.interval:g} s"
        if case.output.snapshots
        else ", no snapshots"
    )
    title = f"{case.title}: " if case.title else ""
    count = getattr(sim.scheme, "total", sim.particles.count)  # over ranks: the whole run's
    budget, source = memory.available()
    return [
        f"{title}{case.solver.scheme} scheme, {count:,} particles, {cells} "
        f"cells of {g.spacing:g} m; about {steps:,} steps of {sim.dt:.3g} s to t = "
        f"{case.time.end:g} s; a row every {case.output.interval:g} s{snaps}"
        + (f", {len(case.probes)} probes" if case.probes else "")
        + f" (about {memory.size(est.disk_bytes)} on disk)",
        f"memory: {est.text()}; the machine can give {memory.size(budget)} ({source})"
        if est.per_rank is None
        else f"memory: the machine can give {memory.size(budget)} ({source}) to the "
        f"{est.per_rank.here} ranks it holds",
        *(est.per_rank.lines() if est.per_rank is not None else []),
    ]
