"""The two schemes the parallel tests compare: a run's scheme over the world's ranks, and the
same run's on this process alone (the reference)."""

from typing import Any

from numpy.typing import NDArray

from mpmflow.particles import Particles
from mpmflow.schemes.projection import ProjectionScheme
from mpmflow.simulation import Simulation


def split(sim: Simulation) -> Simulation:
    """The run's scheme over the world's ranks (on one process: one box)."""
    from mpmflow.parallel.scheme import DistributedProjection  # PETSc's side

    if not isinstance(sim.scheme, DistributedProjection):
        sim.scheme = DistributedProjection(sim.case, sim.grid, sim.particles)
    return sim


def alone(sim: Simulation) -> Simulation:
    """The run's scheme on this process alone (with the whole run: over ranks, gathered
    from the parts)."""
    if type(sim.scheme) is not ProjectionScheme:
        sim.particles = whole(sim)[0]
        sim.scheme = ProjectionScheme(sim.case, sim.grid, sim.particles)
    return sim


def whole(sim: Simulation) -> tuple[Particles, dict[str, NDArray[Any]]]:
    """The run's particles in its order and the scheme's arrays carried by them (with APIC
    ``affine``, a solid's history): over ranks gathered from the parts each holds."""
    gathered = getattr(sim.scheme, "gathered", None)
    if gathered is not None:
        return gathered()  # type: ignore[no-any-return]
    extra = dict(sim.history)
    if getattr(sim.scheme, "affine", None) is not None:
        extra["affine"] = sim.scheme.affine
    return sim.particles, extra
