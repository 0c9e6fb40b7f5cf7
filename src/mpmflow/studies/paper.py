"""The paper's study (Kularathna & Soga 2017, Table 1 and Figs. 2-4), run by one command.

    mpmflow study paper --out DIR [--budget S] [--quick]

For the aspect-ratio-2 column (examples/dam_break.toml) and the aspect-ratio-1 column
(examples/dam_break_ar1.toml), at the paper's meshes 0.0114, 0.008 and 0.004 m (16
particles per cell): the projection scheme with dt = 1e-2, 1e-3, 1e-3 s; the explicit
scheme with the real K = 2.2 GPa at its stable step, for as long as the wall budget allows;
and the explicit scheme with a reduced K (sound speed ten times the free-fall speed
sqrt(2 g H) of the column) to 1.0 s. Explicit runs start from the hydrostatic pressure.
Writes study.csv / study.md (per run: dt, steps, wall time, cost per simulated second,
errors against the references, pressure noise) and the figures (paper_figures).
"""

import csv
import io
import math
import time as _time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..case import Case, load_case
from ..case.shapes import Body
from ..case.shapes import Box as BoxBody
from ..errors import SimulationError
from ..output.atomic import write_text
from ..simulation import Simulation
from .reference_data import G, errors_against_vof, height_error_against_martin_moyce, load

ROOT = Path(__file__).resolve().parents[3]
MESHES = [(0.0114, 1e-2), (0.008, 1e-3), (0.004, 1e-3)]
REAL_K = 2.2e9
SOUND_FACTOR = 10.0  # reduced K: sound speed = this times the free-fall speed sqrt(2 g H)
CRUCHAGA_AR1 = "validation/cruchaga_2007_water_AR1_front_coarse_points_ethersph.csv"
COLUMNS = {
    "ar": "aspect ratio of the column",
    "scheme": "scheme",
    "label": "run",
    "spacing_m": "grid spacing (m)",
    "bulk_modulus_pa": "K (Pa)",
    "dt_s": "dt (s)",
    "mean_dt_s": "mean step (s)",
    "steps": "steps",
    "time_reached_s": "simulated time reached (s)",
    "wall_s": "wall time (s)",
    "wall_per_sim_s": "wall s per simulated s",
    "front_err_a": "front error / a",
    "height_err_a": "height error / a",
    "height_mm_err_a": "height error vs Martin & Moyce / a",
    "front_vs_projection_a": "front difference from projection / a",
    "height_vs_projection_a": "height difference from projection / a",
    "pressure_noise_pa": "mean pressure noise (Pa)",
    "status": "status",
}


# One run's line of study.csv by COLUMNS key: its values are str, int, float or None by
# column, and the code reads them as the column's type (Any, as a csv row's cells).
Row = dict[str, Any]
# time (s) -> (x, pressure) of the particles
Fields = dict[float, tuple[NDArray[np.float64], NDArray[np.float64]]]
# (aspect ratio, example file, label, scheme, overrides, budgeted?)
Planned = tuple[str, str, str, str, list[str], bool]


@dataclass
class RunResult:
    row: Row
    t: NDArray[np.float64]
    front: NDArray[np.float64]
    height: NDArray[np.float64]
    fields: Fields = field(default_factory=dict)


def _box(body: Body) -> BoxBody:
    """The study's columns: the boxes of the dam-break examples."""
    if not isinstance(body, BoxBody):
        raise TypeError(f"the paper study's columns are boxes, not a {body.type}")
    return body


def reduced_bulk_modulus(case: Case, factor: float = SOUND_FACTOR) -> float:
    """K = rho c^2 with c = factor * sqrt(2 g H), H the highest body top (Pa)."""
    top = max(_box(body).max[1] for body in case.bodies)
    c = factor * math.sqrt(2.0 * abs(case.physics.gravity[1]) * top)
    return case.material.density * c * c


def plan(quick: bool = False) -> list[Planned]:
    """The runs of the study: (aspect ratio, example file, label, overrides, budget?)."""
    runs: list[Planned] = []
    meshes = MESHES[:1] if quick else MESHES
    for ar, example in (("2", "examples/dam_break.toml"), ("1", "examples/dam_break_ar1.toml")):
        if quick and ar == "1":
            continue
        base = load_case(ROOT / example)
        k_reduced = reduced_bulk_modulus(base)
        for spacing, dt in meshes:
            common = [
                f"grid.spacing={spacing}",
                "output.snapshot_interval=0.1",
                f"output.snapshots={'true' if spacing == meshes[-1][0] else 'false'}",
            ]
            runs.append(
                (
                    ar,
                    example,
                    f"projection {spacing} m",
                    "projection",
                    common + [f"time.dt={dt}"],
                    False,
                )
            )
            explicit = common + [
                "solver.scheme=explicit",
                "time.dt=auto",
                "bodies.0.initial_pressure=hydrostatic",
            ]
            runs.append(
                (
                    ar,
                    example,
                    f"explicit K = 2.2 GPa {spacing} m",
                    "explicit",
                    explicit + [f"material.bulk_modulus={REAL_K}"],
                    True,
                )
            )
            runs.append(
                (
                    ar,
                    example,
                    f"explicit K = {k_reduced:.3g} Pa {spacing} m",
                    "explicit",
                    explicit + [f"material.bulk_modulus={k_reduced:.6g}"],
                    False,
                )
            )
    return runs


def _errors(
    ar: str,
    t: NDArray[np.float64],
    front: NDArray[np.float64],
    height: NDArray[np.float64],
    a: float,
    t_end: float,
) -> tuple[float, float, float]:
    if ar == "2":
        e = errors_against_vof(t, front, height, a, min(0.2, t_end), min(0.4, t_end))
        tau_end = min(3.5, t_end * math.sqrt(G / a))
        mm = height_error_against_martin_moyce(t, height, a, tau_end)
        return e["front"], e["height"], mm
    pts = load(CRUCHAGA_AR1)
    sel = pts[:, 0] <= min(0.3, t_end) + 1e-9
    diff = np.interp(pts[sel, 0], t, front) / a - pts[sel, 1]
    return float(np.max(np.abs(diff))), float("nan"), float("nan")


def run_one(
    ar: str,
    example: str,
    label: str,
    scheme: str,
    overrides: list[str],
    budgeted: bool,
    out: Path,
    budget: float,
    end: float,
    progress: Callable[[Row], object] | None = None,
) -> RunResult:
    overrides = overrides + [f"time.end={end}"]
    case = load_case(ROOT / example, overrides)
    sim = Simulation(case, out)
    fields: Fields = {}

    def keep(s: Simulation) -> None:
        k = round(s.time / 0.1)
        if abs(s.time - 0.1 * k) < 1e-9 and k >= 1:
            fields[round(0.1 * k, 1)] = (s.particles.x.copy(), s.particles.pressure.copy())

    sim.on_output = keep
    t0 = _time.perf_counter()
    try:
        status = sim.run(wall_budget=budget if budgeted else None)["status"]
    except SimulationError as err:  # reported in the table; the study goes on
        status = f"failed: {err}"
    wall = _time.perf_counter() - t0
    column = _box(case.bodies[0])
    a = column.max[0] - column.min[0]
    t, front, height = sim.series("time"), sim.series("front"), sim.series("height")
    fe, he, mm = _errors(ar, t, front, height, a, sim.time)
    row = {
        "ar": ar,
        "scheme": scheme,
        "label": label,
        "spacing_m": case.grid.spacing,
        "bulk_modulus_pa": case.material.bulk_modulus if scheme == "explicit" else None,
        "dt_s": sim.dt,
        "mean_dt_s": sim.time / sim.steps if sim.steps else float("nan"),
        "steps": sim.steps,
        "time_reached_s": sim.time,
        "wall_s": wall,
        "wall_per_sim_s": wall / sim.time if sim.time > 0 else float("nan"),
        "front_err_a": fe,
        "height_err_a": he,
        "height_mm_err_a": mm,
        "pressure_noise_pa": float(np.mean(sim.series("pressure_noise")[1:])),
        "status": status,
    }
    if progress:
        progress(row)
    return RunResult(row, t, front, height, fields)


def _fmt(v: object) -> str:
    if v is None or (isinstance(v, float) and math.isnan(v)):
        return ""
    if isinstance(v, float):
        return f"{v:.4g}"
    return str(v)


def compare_with_projection(results: Sequence[RunResult], a: float = 0.114) -> None:
    """Largest |explicit - projection| / a of the front (t <= 0.2 s) and the height
    (t <= 0.4 s) at the same column and mesh, over the times both reached."""
    for r in results:
        r.row.setdefault("front_vs_projection_a", None)
        r.row.setdefault("height_vs_projection_a", None)
        if r.row["scheme"] != "explicit":
            continue
        proj = [
            p
            for p in results
            if p.row["scheme"] == "projection"
            and p.row["ar"] == r.row["ar"]
            and p.row["spacing_m"] == r.row["spacing_m"]
        ]
        if not proj:
            continue
        p = proj[0]
        n = min(len(p.t), len(r.t))
        for key, mine, theirs, until in (
            ("front", r.front, p.front, 0.2),
            ("height", r.height, p.height, 0.4),
        ):
            sel = p.t[:n] <= until + 1e-9
            r.row[f"{key}_vs_projection_a"] = float(np.max(np.abs(mine[:n] - theirs[:n])[sel]) / a)


def tables(results: Sequence[RunResult], end: float = 1.0) -> tuple[str, str]:
    """(csv text, markdown text) of the study table and its headline ratios (wall time to
    ``end``, s)."""
    compare_with_projection(results)
    rows = [r.row for r in results]
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(COLUMNS)
    for row in rows:
        w.writerow([_fmt(row[c]) for c in COLUMNS])
    md = [
        "| " + " | ".join(COLUMNS[c] for c in list(COLUMNS)[1:]) + " |",
        "|" + "---|" * (len(COLUMNS) - 1),
    ]
    for ar in ("2", "1"):
        sel = [row for row in rows if row["ar"] == ar]
        if not sel:
            continue
        md.append(f"| **aspect ratio {ar}** |" + " |" * (len(COLUMNS) - 2))
        md += ["| " + " | ".join(_fmt(row[c]) for c in list(COLUMNS)[1:]) + " |" for row in sel]
    md.append("")
    md += headline(rows, end)
    return buf.getvalue(), "\n".join(md) + "\n"


def mean_step(row: Mapping[str, Any]) -> float:
    """The run's mean time step (s): simulated time over steps (time.dt = "auto" re-evaluates
    the explicit step every step, so its first step, dt_s, need not be typical)."""
    return row["time_reached_s"] / row["steps"] if row["steps"] else float("nan")


def wall_to_end(row: Mapping[str, Any], end: float = 1.0) -> tuple[float, str]:
    """(wall seconds to ``end``, how it was obtained): measured when the run reached it, else
    extrapolated linearly from the cost per simulated second up to where it stopped."""
    if row["time_reached_s"] >= end - 1e-9:
        return row["wall_s"], "measured"
    return row["wall_per_sim_s"] * end, (
        f"extrapolated from the {row['time_reached_s']:.3g} s reached ({row['status']})"
    )


def headline(rows: Sequence[Mapping[str, Any]], end: float = 1.0) -> list[str]:
    """At the finest mesh of each column: the time-step and wall-time ratios between the
    projection and each explicit run (real and reduced K), and the pressure noise of each."""
    lines = []
    for ar in ("2", "1"):
        sel = [r for r in rows if r["ar"] == ar]
        if not sel:
            continue
        finest = min(r["spacing_m"] for r in sel)
        here = [r for r in sel if r["spacing_m"] == finest]
        proj = [r for r in here if r["scheme"] == "projection"]
        if not proj:
            continue
        p = proj[0]
        p_wall, p_how = wall_to_end(p, end)
        lines.append(
            f"- Aspect ratio {ar}, {finest:g} m mesh, projection: dt = {p['dt_s']:.3g} s, wall "
            f"time to {end:g} s {p_wall:.4g} s ({p_how}), mean pressure noise "
            f"{p['pressure_noise_pa']:.3g} Pa."
        )
        for e in sorted(
            (r for r in here if r["scheme"] == "explicit"), key=lambda r: -r["bulk_modulus_pa"]
        ):
            e_dt = mean_step(e)
            e_wall, e_how = wall_to_end(e, end)
            lines.append(
                f"  - explicit, K = {e['bulk_modulus_pa']:.3g} Pa: mean step {e_dt:.3g} s, "
                f"time-step ratio projection / explicit {p['dt_s'] / e_dt:.0f}; wall time to "
                f"{end:g} s {e_wall:.4g} s ({e_how}), ratio to the projection "
                f"{e_wall / p_wall:.3g}; mean pressure noise {e['pressure_noise_pa']:.3g} Pa."
            )
    return lines


def run_study(
    out: str | Path,
    budget: float = 480.0,
    quick: bool = False,
    end: float = 1.0,
    progress: Callable[[Row], object] | None = None,
) -> list[RunResult]:
    """Run the study into ``out``; returns the RunResults."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    results = []
    for k, (ar, example, label, scheme, overrides, budgeted) in enumerate(plan(quick)):
        folder = out / "runs" / f"ar{ar}_{k:02d}_{label.replace(' ', '_').replace('=', '')}"
        results.append(
            run_one(ar, example, label, scheme, overrides, budgeted, folder, budget, end, progress)
        )
        csv_text, md_text = tables(results, end)
        write_text(out / "study.csv", csv_text)
        write_text(out / "study.md", md_text)
    from .paper_figures import write_figures

    write_figures(results, out)
    return results
