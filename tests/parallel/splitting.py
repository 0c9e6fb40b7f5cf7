"""The two schemes the parallel tests compare: a run's scheme over the world's ranks, and the
same run's on this process alone (the reference)."""

from mpmflow.schemes.projection import ProjectionScheme
from mpmflow.simulation import Simulation


def split(sim: Simulation) -> Simulation:
    """The run's scheme over the world's ranks (on one process: one box)."""
    from mpmflow.parallel.scheme import DistributedProjection  # PETSc's side

    if not isinstance(sim.scheme, DistributedProjection):
        sim.scheme = DistributedProjection(sim.case, sim.grid, sim.particles)
    return sim


def alone(sim: Simulation) -> Simulation:
    """The run's scheme on this process alone."""
    if type(sim.scheme) is not ProjectionScheme:
        sim.scheme = ProjectionScheme(sim.case, sim.grid, sim.particles)
    return sim
