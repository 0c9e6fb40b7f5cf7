"""timeseries.csv: one row per output time; the header names the columns (units in the README
and in summary.json)."""

import math

from .atomic import write_text

COLUMNS = {
    "time": "s",
    "front": "m",
    "height": "m",
    "step": "-",
    "kinetic_energy": "J/m",
    "potential_energy": "J/m",
    "max_speed": "m/s",
    "max_pressure": "Pa",
    "pressure_noise": "Pa",
    "volume_ratio": "-",
    "packed_share": "-",
    "max_particles_per_cell": "-",
    "pressure_unknowns": "-",
    "solver_iterations": "-",
}


def _fmt(value):
    if isinstance(value, int):
        return str(value)
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "nan"
    return f"{value:.9g}"


class TimeSeriesWriter:
    """Keeps the rows and rewrites the whole (small) file atomically after each row."""

    def __init__(self, path, rows=()):
        """``rows``: those already written by the run being continued (from a checkpoint);
        the file is rewritten with them at once, dropping any rows written after it."""
        self.path = path
        self.rows = [",".join(_fmt(row[c]) for c in COLUMNS) for row in rows]
        if self.rows:
            self._write()

    def append(self, row):
        self.rows.append(",".join(_fmt(row[c]) for c in COLUMNS))
        self._write()

    def _write(self):
        write_text(self.path, ",".join(COLUMNS) + "\n" + "\n".join(self.rows) + "\n")
