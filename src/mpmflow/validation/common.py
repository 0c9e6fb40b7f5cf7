"""Shared pieces of the validation cases: result rows, a case's result, running a case.

Every row carries its tolerance and a one-line justification, fixed in the case module
before the results were looked at; a row passes when its value is on the allowed side of
the tolerance (a value that could not be measured, nan, fails).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from types import ModuleType
from typing import TYPE_CHECKING, Any, Literal

import numpy as np
from numpy.typing import ArrayLike

from ..case import load_case
from ..case.shapes import Body
from ..case.shapes import Box as BoxBody
from ..plotting import mpl
from ..simulation import Simulation

if TYPE_CHECKING:
    from matplotlib.figure import Figure

ROOT = Path(__file__).resolve().parents[3]
EXAMPLES = ROOT / "examples"


@dataclass
class Row:
    """One line of the summary table."""

    case: str
    quantity: str
    measure: str
    value: float
    tolerance: float
    justification: str
    unit: str = ""
    sense: str = "<="  # "<=": the value must not exceed the tolerance; ">=": not fall below;
    # "|<=|": its magnitude must not exceed the tolerance (signed values)
    miss: str = ""  # why a miss of this row happens (shown only when it misses)
    not_measurable: bool = False  # nan because there is nothing to measure (see ``miss``)

    @property
    def status(self) -> Literal["pass", "miss", "n/a"]:
        """ "pass", "miss", or "n/a" (nothing to measure, explained in ``miss``)."""
        if self.not_measurable and not math.isfinite(self.value):
            return "n/a"
        return "pass" if self.passed else "miss"

    @property
    def passed(self) -> bool:
        v = self.value
        if v is None or not math.isfinite(v):
            return False
        if self.sense == "|<=|":
            return abs(v) <= self.tolerance
        return v <= self.tolerance if self.sense == "<=" else v >= self.tolerance

    @property
    def tolerance_text(self) -> str:
        return {"<=": "<= ", ">=": ">= ", "|<=|": "|x| <= "}[self.sense] + f"{self.tolerance:.3g}"

    def as_dict(self) -> dict[str, str | float]:
        return {
            "case": self.case,
            "quantity": self.quantity,
            "measure": self.measure,
            "value": self.value,
            "tolerance": self.tolerance_text,
            "unit": self.unit,
            "status": self.status,
            "justification": self.justification,
        }


@dataclass
class CaseResult:
    """What a validation case returns: rows for the table, figures, and its report section."""

    name: str
    title: str
    rows: list[Row] = field(default_factory=list)
    figures: list[tuple[str, str]] = field(default_factory=list)  # (file name, caption)
    text: str = ""  # Markdown: set-up, measures, per-run numbers
    wall_s: float = 0.0


def run_example(
    example: str,
    overrides: Sequence[str] = (),
    on_output: Callable[[Simulation], None] | None = None,
) -> Simulation:
    """Run ``examples/<example>`` with overrides (no files written); returns the Simulation.

    ``on_output(sim)`` is called at every output time. The run's wall time is in
    ``sim.summary['wall_seconds']``."""
    case = load_case(EXAMPLES / example, ["output.snapshots=false", *overrides])
    sim = Simulation(case)
    if on_output is not None:
        sim.on_output = on_output
    sim.run()
    return sim


def parabola_extremum(t: np.ndarray, s: np.ndarray, k: int) -> tuple[float, float]:
    """The extremum (time, value) of the parabola through the samples k - 1, k, k + 1 of the
    signal s(t) (evenly spaced times; the sample k itself where the three lie on a line)."""
    y0, y1, y2 = s[k - 1], s[k], s[k + 1]
    d = y0 - 2 * y1 + y2
    off = 0.5 * (y0 - y2) / d if d != 0 else 0.0
    return float(t[k] + off * (t[k + 1] - t[k])), float(y1 - 0.25 * (y0 - y2) * off)


def observed_order(h: ArrayLike, e: ArrayLike) -> float:
    """Least-squares slope of log(error) against log(spacing): the observed order."""
    h, e = np.asarray(h, float), np.asarray(e, float)
    if np.any(~np.isfinite(e)) or np.any(e <= 0):
        return float("nan")
    return float(np.polyfit(np.log(h), np.log(e), 1)[0])


def fmt(v: float | np.integer[Any] | None, digits: int = 3) -> str:
    """A number for the report: 3 significant digits, nan as 'n/a'."""
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return "n/a"
    if isinstance(v, (int, np.integer)):
        return str(v)
    return f"{v:.{digits}g}"


def markdown_table(header: Sequence[str], rows: Iterable[Sequence[object]]) -> str:
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(str(c) for c in row) + " |" for row in rows]
    return "\n".join(lines)


DPI = 90  # of the report's figures


def pyplot() -> ModuleType:
    """matplotlib.pyplot (see ``plotting.mpl``)."""
    return mpl.pyplot("mpmflow validate")


def save(fig: Figure, path: Path) -> None:
    """Save a report figure atomically and close it."""
    mpl.save(fig, path, DPI)


def box(body: Body) -> BoxBody:
    """A validation case's body, which is a box in each example it runs (its corners are
    read): TypeError for another shape."""
    if not isinstance(body, BoxBody):
        raise TypeError(f"the validation expects a box body here, not a {body.type}")
    return body
