"""What the steps did, summed over the run (summary.json's solver statistics, the caps and
fallbacks that acted); checkpoints carry them."""

from dataclasses import dataclass
from typing import Protocol

from ..case import Case
from ..fallbacks import Fallbacks


@dataclass
class Counters:
    moved_inside: int = 0
    solves: int = 0
    iterations: int = 0
    iterations_since_output: int = 0
    max_iterations: int = 0
    max_unknowns: int = 0
    released: int = 0
    worst_residual: float = 0.0
    viscous_iterations: int = 0
    plastic_iterations: int = 0  # the coupled step's (State::plastic_solve)


class ChunkReport(Protocol):
    """What every scheme's report of a chunk holds (``Scheme.advance``); ``capped``,
    ``clamped``, ``pockets``, ``unsettled``, ``viscous_iterations``, ``plastic_iterations``
    and ``steps`` only some (0 or the chunk's steps when absent)."""

    moved_inside: int
    solves: int
    iterations: int
    max_iterations: int
    unknowns: int
    released: int
    residual: float


def add_report(
    c: Counters, fallbacks: Fallbacks, report: ChunkReport, case: Case, time: float
) -> None:
    """Add the scheme's ``report`` of a chunk ending at ``time`` to the counters ``c`` and
    to ``fallbacks`` (``mpmflow.fallbacks.Fallbacks``)."""
    c.moved_inside += report.moved_inside
    fallbacks.count(
        "particles put back inside the domain or out of an obstacle",
        "domain walls and obstacles",
        report.moved_inside,
        time,
    )
    fallbacks.count(
        "viscosity held at material.max_viscosity",
        f"material ({case.material.model})",
        getattr(report, "capped", 0),
        time,
    )
    fallbacks.count(
        "volume correction displacement clamped at half a cell per step",
        "solver.volume_correction",
        getattr(report, "clamped", 0),
        time,
    )
    fallbacks.count(
        "water sealed from the free surface held at p = 0 at its top",
        "pressure system",
        getattr(report, "pockets", 0),
        time,
    )
    fallbacks.count(
        "walls' contact not settled in 50 rounds: the last round's pressure used",
        "pressure system (docs/method.md, Energy)",
        getattr(report, "unsettled", 0),
        time,
    )
    c.solves += report.solves
    c.iterations += report.iterations
    c.iterations_since_output += report.iterations
    c.max_iterations = max(c.max_iterations, report.max_iterations)
    c.max_unknowns = max(c.max_unknowns, report.unknowns)
    c.released += report.released
    c.worst_residual = max(c.worst_residual, report.residual)
    c.viscous_iterations += getattr(report, "viscous_iterations", 0)
    c.plastic_iterations += getattr(report, "plastic_iterations", 0)
