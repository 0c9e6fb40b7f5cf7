"""Time-step study (issue 39): the paper's dam break (aspect ratio 2, examples/dam_break.toml)
at 0.008 m and 0.004 m with dt = 2, 1, 0.5, 0.25, 0.1 and 0.05 ms, with the default transfer
(FLIP, 1% PIC per millisecond) and with APIC, to t = 1 s.

A projection is stable for any step, and a smaller step must give a better answer: the
energy of the water in its closed tank may fall, never rise, whatever dt, and the front and
the column height must converge as dt falls. Measures:

* **energy**: the largest (KE + PE) / (KE + PE at t = 0) - 1 over the output times (every
  0.01 s; PE from the tank's floor, so the start is the column's potential energy, 29 J/m);
* **convergence**: the largest difference of the front (t <= 0.2 s) and of the column height
  (t <= 0.4 s), in units of the column width a, between runs with successive steps, and the
  observed order of those differences against dt (least-squares slope of log difference
  against log dt over the successive pairs).
"""

from pathlib import Path

import numpy as np

from .common import CaseResult, Row, fmt, markdown_table, observed_order, pyplot, run_example, save
from .types import Context, Measures

A = 0.114  # m, the column's width
MESHES, MESHES_QUICK = (0.008, 0.004), (0.008,)
DTS, DTS_QUICK = (2e-3, 1e-3, 5e-4, 2.5e-4, 1e-4, 5e-5), (1e-3, 5e-4, 2.5e-4)
TRANSFERS, TRANSFERS_QUICK = ("flip", "apic"), ("flip",)
END, END_QUICK = 1.0, 0.3  # s

# tolerances, fixed before the results were looked at (issue 39)
TOL_ENERGY = 0.005
WHY_ENERGY = (
    "a closed inviscid tank may lose energy, never gain it; 0.5% is the issue's bound, 15 "
    "times the largest rise the long runs show at the default step (0.03% over 20 s)"
)
TOL_ORDER = 0.5
WHY_ORDER = (
    "the step is first order in time, so successive differences halve with dt (order 1); "
    "0.5 leaves room for the output-time sampling of the f = 1/2 crossings"
)


def _run(h: float, dt: float, transfer: str, end: float) -> Measures:
    sim = run_example(
        "dam_break.toml",
        [f"grid.spacing={h}", f"time.dt={dt}", f"time.end={end}", f'solver.transfer="{transfer}"'],
    )
    e = sim.series("kinetic_energy") + sim.series("potential_energy")
    return {
        "h": h,
        "dt": dt,
        "transfer": transfer,
        "t": sim.series("time"),
        "front": sim.series("front"),
        "height": sim.series("height"),
        "energy": e / e[0],
        "gain": float(np.max(e / e[0]) - 1.0),
        "speed": float(np.nanmax(sim.series("max_speed"))),
        "wall": float(sim.summary["wall_seconds"]),
    }


def _difference(r: Measures, s: Measures, key: str, until: float) -> float:
    """Largest |r - s| / a of one measure over the output times t <= until."""
    sel = s["t"] <= until + 1e-9
    d = np.interp(s["t"][sel], r["t"], r[key]) - s[key][sel]
    return float(np.max(np.abs(d)) / A)


def run(out: Path, quick: bool = False, context: Context | None = None) -> CaseResult:
    meshes = MESHES_QUICK if quick else MESHES
    dts = DTS_QUICK if quick else DTS
    transfers = TRANSFERS_QUICK if quick else TRANSFERS
    end = END_QUICK if quick else END
    res = CaseResult("time_step_study", "Time-step study: the dam break from 2 ms to 0.05 ms")
    runs: dict[tuple[float, str], list[Measures]] = {}
    for h in meshes:
        for transfer in transfers:
            series = runs[(h, transfer)] = [_run(h, dt, transfer, end) for dt in dts]
            for r in series:
                res.rows.append(
                    Row(
                        "time step",
                        f"energy, h = {h:g} m, {transfer}, dt = {r['dt']:g} s",
                        f"largest (KE + PE) / start - 1, t <= {end:g} s",
                        r["gain"],
                        TOL_ENERGY,
                        WHY_ENERGY,
                        miss="the sub-cell surface's ghost pressure makes the projection "
                        "step gain a little energy at each step once the surge meets the "
                        "wall, more the smaller the step; the node surface gains none "
                        "(issue 39; docs/method.md, 'Energy')",
                    )
                )
            for key, until in (("front", 0.2), ("height", 0.4)):
                diffs = [
                    _difference(a, b, key, until) for a, b in zip(series, series[1:], strict=False)
                ]
                res.rows.append(
                    Row(
                        "time step",
                        f"{key} convergence, h = {h:g} m, {transfer}",
                        "observed order in dt of successive largest differences",
                        observed_order([r["dt"] for r in series[1:]], diffs)
                        if len(diffs) >= 2
                        else float("nan"),
                        TOL_ORDER,
                        WHY_ORDER,
                        sense=">=",
                        miss="the differences do not shrink with the step",
                        not_measurable=len(diffs) < 2,
                    )
                )
                for r, d in zip(series, diffs, strict=False):
                    r[f"{key}_diff"] = d
    _figure(out, runs)
    res.figures.append(
        (
            "time_step_study.png",
            "Energy (KE + PE) relative to the start against time, one panel per mesh and "
            "transfer, one line per step.",
        )
    )
    res.text = _text(runs, end)
    return res


def _figure(out: Path, runs: dict[tuple[float, str], list[Measures]]) -> None:
    plt = pyplot()
    fig, axes = plt.subplots(1, len(runs), figsize=(5 * len(runs), 4), squeeze=False)
    for ax, ((h, transfer), series) in zip(axes[0], runs.items(), strict=True):
        for r in series:
            ax.plot(r["t"], r["energy"], label=f"dt = {r['dt']:g} s")
        ax.axhline(1 + TOL_ENERGY, color="k", ls=":", lw=0.8)
        ax.set(xlabel="t [s]", ylabel="(KE + PE) / start [-]", title=f"h = {h:g} m, {transfer}")
        ax.set_yscale("log")
        ax.legend(fontsize=7)
    fig.tight_layout()
    save(fig, out / "time_step_study.png")


def _text(runs: dict[tuple[float, str], list[Measures]], end: float) -> str:
    doc = __doc__.split("\n\n", 1)[1].strip()
    rows = [
        [
            h,
            transfer,
            r["dt"],
            fmt(r["gain"]),
            fmt(r["speed"]),
            fmt(r.get("front_diff")),
            fmt(r.get("height_diff")),
            fmt(r["wall"]),
        ]
        for (h, transfer), series in runs.items()
        for r in series
    ]
    table = markdown_table(
        [
            "h (m)",
            "transfer",
            "dt (s)",
            f"largest energy rise, t <= {end:g} s",
            "largest speed (m/s)",
            "front: largest difference to the next step (a)",
            "height: largest difference to the next step (a)",
            "wall (s)",
        ],
        rows,
    )
    return doc + "\n\n" + table
