"""Time-integration schemes, registered by the name used in ``solver.scheme``, each
declaring what it supports (``SUPPORTS``): the case's rules ask here instead of naming
schemes."""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any, ClassVar, Protocol

from numpy.typing import NDArray

if TYPE_CHECKING:  # the case asks this registry what each scheme supports
    from ..case import Case
    from ..grid import Grid
    from ..particles import Particles
    from .projection import StepReport

from ..boundaries.outlets import Outflow


class Scheme(Protocol):
    """What the Simulation asks of a scheme (``projection``, ``explicit``)."""

    SUPPORTS: ClassVar[frozenset[str]]  # the FEATURES it supports
    last_unknowns: int  # the size of the last step's system (0: none)
    particles: Particles  # the particles it moves (set anew before the first step: setup)
    outflow: Outflow  # what has left through the domain's outlets

    def __init__(self, case: Case, grid: Grid, particles: Particles) -> None: ...

    def advance(self, dt: float, nsteps: int, where: Callable[[int], str]) -> StepReport:
        """nsteps steps of dt (s) on the particles, in place; a report of what they did."""
        ...

    def state(self) -> dict[str, NDArray[Any]]:
        """What a checkpoint keeps of the scheme besides the particles (arrays of any
        dtype)."""
        ...

    def restore(self, saved: dict[str, NDArray[Any]]) -> None:
        """Put back what ``state`` returned."""
        ...


SCHEMES: dict[str, type[Scheme]] = {}

# The features a scheme may support, as the case's rules name them to the user.
FEATURES = {
    "obstacles": "fixed obstacles ([[obstacles]])",
    "materials": "materials other than inviscid water (material.model)",
    "periodic": "periodic axes (domain.periodic)",
    "apic": 'APIC transfers (solver.transfer = "apic"; it transfers by FLIP/PIC only)',
    "outlets": 'outlets (domain.walls = "outlet")',
}


def _load() -> None:
    from . import explicit, projection  # noqa: F401  (they register themselves)


def supports(name: str, feature: str) -> bool:
    """True when scheme ``name`` supports ``feature`` (a key of FEATURES)."""
    _load()
    return feature in SCHEMES[name].SUPPORTS


def supporting(feature: str) -> list[str]:
    """The names of the schemes that support ``feature``."""
    _load()
    return [name for name, cls in SCHEMES.items() if feature in cls.SUPPORTS]


def register(name: str) -> Callable[[type[Scheme]], type[Scheme]]:
    def deco(cls: type[Scheme]) -> type[Scheme]:
        SCHEMES[name] = cls
        return cls

    return deco


def make_scheme(case: Case, grid: Grid, particles: Particles) -> Scheme:
    """The case's scheme; started on several MPI processes, its form over the ranks
    (``parallel.scheme``)."""
    _load()
    from ..parallel.comm import launched_size

    if launched_size() > 1:
        from ..parallel.support import distributed

        return distributed(case, grid, particles)
    return SCHEMES[case.solver.scheme](case, grid, particles)
