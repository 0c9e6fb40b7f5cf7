"""Time-integration schemes, registered by the name used in ``solver.scheme``. What each
supports is data in ``case.capabilities`` (the case's rules read it there without loading
the schemes); each class's ``SUPPORTS`` is its entry of that table."""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any, ClassVar, Protocol

from numpy.typing import NDArray

if TYPE_CHECKING:
    from ..case import Case
    from ..grid import Grid
    from ..particles import Particles
    from .projection import StepReport

from ..boundaries.inlets import Inflow
from ..boundaries.outlets import Outflow


class Scheme(Protocol):
    """What the Simulation asks of a scheme (``projection``, ``explicit``)."""

    SUPPORTS: ClassVar[frozenset[str]]  # the capabilities.FEATURES it supports
    last_unknowns: int  # the size of the last step's system (0: none)
    particles: Particles  # the particles it moves (set anew before the first step: setup)
    outflow: Outflow  # what has left through the domain's outlets
    inflow: Inflow  # what has entered through its inlets

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


def registry() -> dict[str, type[Scheme]]:
    """Every scheme by its ``solver.scheme`` name (importing their modules, which load the
    compiled core; the names are ``case.capabilities.SUPPORTS``'s)."""
    from .explicit import ExplicitScheme
    from .projection import ProjectionScheme

    return {"projection": ProjectionScheme, "explicit": ExplicitScheme}
