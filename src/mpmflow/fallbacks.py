"""The caps, clamps and fallbacks that acted during a run, counted (summary.json's
``caps_and_fallbacks``; the run's last line says when any did).

A cap or a fallback changes an answer: a probe that reads its window's mean because too
few particles lie in it, a viscosity held at ``material.max_viscosity``, a particle put
back inside the domain. None of them is an error, and none may pass without a word:
each place that applies one counts it here, under a fixed text (``WHAT``) and where it
acted (a probe's name, a setting). Counts are kept in checkpoints, so a restarted run
reports the whole run.
"""

from collections.abc import Iterable
from typing import TypedDict


class Row(TypedDict):
    """One count: what acted, where, how often (in ``unit``), and when first and last (s)."""

    what: str
    where: str
    count: int
    unit: str
    first_time: float | None
    last_time: float | None


# what acted -> the unit its count is in
WHAT = {
    "probe fit fell back to the window mean": "outputs",
    "probe fit below 0 read as 0": "outputs",
    "level gauge reached the grid's top": "outputs",
    "particles put back inside the domain or out of an obstacle": "particle-steps",
    "viscosity held at material.max_viscosity": "cell-steps",
    "volume correction displacement clamped at half a cell per step": "face-steps",
    "water sealed from the free surface held at p = 0 at its top": "pocket-steps",
    "walls' contact not settled in 50 rounds: the last round's pressure used": "steps",
}


class Fallbacks:
    """Counts of the caps and fallbacks that acted: ``count(what, where, n, time)``."""

    def __init__(self, rows: Iterable[Row] = ()) -> None:
        self._rows: dict[tuple[str, str], Row] = {}
        for r in rows:  # from a checkpoint's ``rows()``
            self._rows[(r["what"], r["where"])] = r.copy()

    def count(self, what: str, where: str, n: int = 1, time: float | None = None) -> None:
        """Record that ``what`` (a key of WHAT) acted ``n`` times at ``where`` (text) at
        ``time`` (s; the first and last are kept)."""
        if n <= 0:
            return
        if what not in WHAT:
            raise KeyError(f"unknown fallback {what!r}")
        row = self._rows.setdefault(
            (what, where),
            {
                "what": what,
                "where": where,
                "count": 0,
                "unit": WHAT[what],
                "first_time": time,
                "last_time": time,
            },
        )
        row["count"] += int(n)
        if time is not None:
            if row["first_time"] is None:
                row["first_time"] = time
            row["last_time"] = time

    def rows(self) -> list[Row]:
        """The counts as a list of dicts (what, where, count, unit, first_time, last_time
        (s)), in a fixed order."""
        return [self._rows[k].copy() for k in sorted(self._rows)]

    def __bool__(self) -> bool:
        return bool(self._rows)

    def line(self) -> str | None:
        """One sentence for the run's last line: what acted and how often (None: nothing)."""
        if not self._rows:
            return None
        parts = [f"{r['what']} ({r['where']}: {r['count']} {r['unit']})" for r in self.rows()]
        return (
            f"{len(parts)} cap{'s' if len(parts) > 1 else ''} or fallback"
            f"{'s' if len(parts) > 1 else ''} acted during the run: "
            + "; ".join(parts)
            + " (summary.json, caps_and_fallbacks)"
        )
