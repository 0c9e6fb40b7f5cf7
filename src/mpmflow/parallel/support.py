"""What a run over several MPI ranks supports yet (issue 28): the case's settings that the
split scheme (``parallel.scheme``) does not run are refused by name, with the setting to
change, before anything is built."""

from __future__ import annotations

from typing import TYPE_CHECKING

from .. import materials
from ..boundaries import outlets
from ..errors import CaseError
from ..grid import Grid
from ..particles import Particles

if TYPE_CHECKING:
    from ..case import Case
    from ..schemes.projection import ProjectionScheme


def refusals(case: Case) -> list[str]:
    """What this first decomposition does not run yet, each with the setting to change."""
    s = case.solver
    out = []
    if s.scheme != "projection":
        out.append(f'solver.scheme = "{s.scheme}" runs on one process: use "projection"')
    if case.domain.periodic and any(case.domain.periodic):
        out.append("periodic axes are not split over ranks yet: remove domain.periodic")
    if (
        materials.is_solid(case.material)
        and case.time.dt != "auto"
        and materials.coupled_step(case.material, case.grid.spacing, float(case.time.dt))
    ):
        step = materials.shear_wave_step(case.material, case.grid.spacing)
        out.append(
            f"a solid's steps past its shear wave's ({step:.3g} s on this grid) take the "
            "coupled elastic-pressure solve, which is not split over ranks yet: set "
            f'time.dt to at most {step:.3g} s, or time.dt = "auto"'
        )
    if any(case.domain.bonded_sides()):
        out.append('bonded walls are not split over ranks yet: make them "no_slip"')
    if case.inlets:
        out.append("inlets are not split over ranks yet: remove the [[inlets]]")
    if case.sponges:
        out.append("damping zones are not split over ranks yet: remove the [[sponges]]")
    if case.plate is not None:
        out.append("a plate is not split over ranks yet: remove the [plate]")
    if case.loads:
        out.append("surface loads are not split over ranks yet: remove the [[loads]]")
    if case.material.model in materials.SATURATED:
        out.append(
            f"a saturated soil (material.model = {case.material.model!r}) takes the coupled "
            "elastic-pressure solve at every step and its pore flow between the cells, which "
            "are not split over ranks yet: run it on one process"
        )
    if s.linear_solver in ("amg", "direct"):
        out.append(
            f'solver.linear_solver = "{s.linear_solver}" runs on one process: on several '
            'ranks the pressure is solved by PETSc ("petsc", or the default "multigrid")'
        )
    return out


def distributed(case: Case, grid: Grid, particles: Particles) -> ProjectionScheme:
    """The case's scheme over the run's MPI ranks, or a CaseError naming what it lacks."""
    missing = refusals(case)
    if outlets.sides(case).any():
        missing.append("outlets are not split over ranks yet: close domain.walls' outlets")
    if missing:
        raise CaseError(
            "This case cannot run on several MPI ranks yet (issue 28, first "
            "decomposition): " + "; ".join(missing) + ". Or run it on one process."
        )
    from .scheme import DistributedProjection  # imports PETSc's side

    return DistributedProjection(case, grid, particles)
