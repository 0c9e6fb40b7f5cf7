"""Dam breaks: aspect ratio 2 at the paper's three meshes, time-step independence (aspect
ratio 1: ``dam_break_ar1``).

Aspect ratio 2 (examples/dam_break.toml): column a = 0.114 m wide, 2a high, tank 0.42 m
long, 1.0 s. Every mesh runs with the same time-step rule, dt = 1 ms (Courant number
|v| dt / h at most about 0.6 at 0.004 m); the paper's coarse case (0.0114 m with its
dt = 10 ms, Courant number about 2) is an extra row. Error measures, lengths in units of a:

* **front vs an experiment** (Martin & Moyce Table 2, Koshizuka & Oka): RMS of
  (x_sim - x_ref) / a over the reference points before the wall impact (Z = x/a < 0.42 m / a),
  the simulated front interpolated linearly to the reference times (T = t sqrt(2 g / a));
* **height vs Martin & Moyce Table 6**: the largest |eta_sim - eta_ref| / a over the points
  with tau = t sqrt(g / a) <= 3.5;
* **front vs VOF**: RMS over the VOF rows with t <= 0.2 s (before the impact at ~0.22 s);
  **height vs VOF**: the largest difference over t <= 0.4 s;
* **mesh convergence**: the observed order of the front and height errors against VOF over
  the three meshes (least-squares slope of log error against log spacing).
"""

import math
from collections.abc import Callable
from pathlib import Path

import numpy as np

from ..simulation import Simulation
from ..studies.reference_data import errors_against_vof, height_error_against_martin_moyce, load
from .common import CaseResult, Row, fmt, markdown_table, observed_order, pyplot, run_example, save
from .types import Context, FloatArray, Measures
from .volume import Recorder

G = 9.81
A = 0.114  # m, column width
TANK = 0.42  # m
MM_FRONT = "validation/martin_moyce_1952_n2eq2_a2.25in_front_table2.csv"
MM_HEIGHT = "validation/martin_moyce_1952_n2eq2_a2.25in_height_table6.csv"
KO_FRONT = "validation/koshizuka_oka_1996_front_experiment_digitised_pysph.csv"
VOF = "reference/vof_interfoam_ar2_dx0.004_slip.csv"

MESHES, MESHES_QUICK = (0.0114, 0.008, 0.004), (0.008,)
DT = 1e-3  # s, the time-step rule of every mesh
PAPER_COARSE = (0.0114, 1e-2)  # the paper's coarse case, an extra row
DTS = (2e-3, 1e-3, 5e-4)  # time-step independence at 0.008 m
END, END_QUICK = 1.0, 0.45  # s (quick: past tau = 3.5 at 0.377 s)

# tolerances, fixed before the results were looked at
EXTRA = 0.05
WHY_FRONT_EXP = (
    "the inviscid VOF reference's own RMS distance from these points ({:.2f} a: "
    "gate release and bed friction slow the experiment) plus 0.05 a"
)
TOL_HEIGHT_MM = 0.08
WHY_HEIGHT_MM = (
    "the issue's criterion; Table 6 steps eta by 0.11 a (0.25 in), so 0.08 a is "
    "within one reading step"
)
TOL_FRONT_VOF = 0.05
WHY_FRONT_VOF = (
    "the VOF is a 0.004 m solution of the same inviscid equations: 0.05 a = 5.7 mm,"
    " half a cell of the coarsest mesh"
)
TOL_HEIGHT_VOF = 0.07
WHY_HEIGHT_VOF = "the project's acceptance floor; below the 0.08 a allowed against experiment"
TOL_ORDER = 0.5
WHY_ORDER = (
    "the errors must shrink with the mesh; bilinear MPM with FLIP converges at first "
    "order at best, and the VOF reference has its own 0.004 m error, so 0.5"
)
TOL_DT = {1e-3: 0.02, 2e-3: 0.04}
WHY_DT = {
    1e-3: "a quarter of the 0.08 a height tolerance: the time step must not decide a "
    "comparison with data",
    2e-3: "half of the 0.08 a height tolerance at twice the default step (Courant ~0.6 at 0.008 m)",
}


def front_rms(t: FloatArray, front: FloatArray, data: str, scale: float) -> float:
    """RMS of (x_sim - x_ref) / a over the data points before the wall (T = t * scale)."""
    ref = load(data)
    sel = (ref[:, 1] < TANK / A) & (ref[:, 0] > 0)
    tr = ref[sel, 0] / scale
    ok = tr <= t[-1] + 1e-9
    diff = np.interp(tr[ok], t, front) / A - ref[sel, 1][ok]
    return float(np.sqrt(np.mean(diff**2))) if diff.size else float("nan")


def front_errors(t: FloatArray, front: FloatArray) -> tuple[float, float]:
    """RMS front errors against Martin & Moyce Table 2 and Koshizuka & Oka (units of a)."""
    s = math.sqrt(2 * G / A)
    return front_rms(t, front, MM_FRONT, s), front_rms(t, front, KO_FRONT, s)


def vof_front_allowance() -> tuple[float, float]:
    """The tolerances of the experiment comparisons: the VOF's own RMS error plus EXTRA."""
    vof = load(VOF)
    mm, ko = front_errors(vof[:, 0], vof[:, 1])
    return mm + EXTRA, ko + EXTRA


def _run_ar2(
    h: float, dt: float, end: float, on_output: Callable[[Simulation], None] | None = None
) -> Measures:
    sim = run_example(
        "dam_break.toml",
        [f"grid.spacing={h}", f"time.dt={dt}", f"time.end={end}"],
        on_output=on_output,
    )
    t, front, height = sim.series("time"), sim.series("front"), sim.series("height")
    vof = errors_against_vof(
        t, front, height, A, front_until=min(0.2, end), height_until=min(0.4, end)
    )
    mm, ko = front_errors(t, front)
    s = sim.summary
    return {
        "h": h,
        "dt": dt,
        "t": t,
        "front": front,
        "height": height,
        "front_vof": vof["front_rms"],
        "height_vof": vof["height"],
        "front_mm": mm,
        "front_ko": ko,
        "height_mm": height_error_against_martin_moyce(t, height, A, 3.5),
        "particles": s["particles"],
        "lost": s["particles_lost"],
        "inside": s["particles_moved_inside"],
        "mass": s["mass_relative_change"],
        "ppc": s["max_particles_per_cell"],
        "wall": s["wall_seconds"],
    }


def run(out: Path, quick: bool = False, context: Context | None = None) -> CaseResult:
    meshes = MESHES_QUICK if quick else MESHES
    end = END_QUICK if quick else END
    res = CaseResult("dam_break", "Dam break, aspect ratio 2")
    runs = []
    for h in meshes:
        finest = h == meshes[-1]
        rec = Recorder() if finest else None
        runs.append(_run_ar2(h, DT, end, rec))
        if rec is not None and context is not None:
            context.setdefault("volume", {})["dam break"] = (f"h = {h} m", rec)
    paper = None if quick else _run_ar2(*PAPER_COARSE, end)
    tol_mm, tol_ko = vof_front_allowance()
    name = "dam break AR2"
    for r in runs + ([paper] if paper else []):
        tag = f"h = {r['h']} m, dt = {r['dt']:g} s"
        extra = r is paper
        res.rows.append(
            Row(
                name,
                f"height, {tag}",
                "max |eta - eta_M&M Table 6| / a, tau <= 3.5",
                r["height_mm"],
                TOL_HEIGHT_MM,
                WHY_HEIGHT_MM,
                miss="the paper's dt = 10 ms is a Courant number of about 2: the "
                "column falls too slowly in the first steps, a time-step error"
                " (the same mesh at dt = 1 ms is the row above)"
                if extra
                else "the column height lags the experiment",
            )
        )
        if extra:
            continue
        res.rows.append(
            Row(
                name,
                f"front vs M&M, {tag}",
                "RMS (x - x_ref) / a before the wall",
                r["front_mm"],
                tol_mm,
                WHY_FRONT_EXP.format(tol_mm - EXTRA),
                miss="the experiment's front is slower than inviscid theory",
            )
        )
        res.rows.append(
            Row(
                name,
                f"front vs K&O, {tag}",
                "RMS (x - x_ref) / a before the wall",
                r["front_ko"],
                tol_ko,
                WHY_FRONT_EXP.format(tol_ko - EXTRA),
                miss="the experiment's front is slower than inviscid theory",
            )
        )
        res.rows.append(
            Row(
                name,
                f"front vs VOF, {tag}",
                "RMS (x - x_VOF) / a, t <= 0.2 s",
                r["front_vof"],
                TOL_FRONT_VOF,
                WHY_FRONT_VOF,
                miss="the coarse mesh resolves the thin surge tip with a few particles",
            )
        )
        res.rows.append(
            Row(
                name,
                f"height vs VOF, {tag}",
                "max |eta - eta_VOF| / a, t <= 0.4 s",
                r["height_vof"],
                TOL_HEIGHT_VOF,
                WHY_HEIGHT_VOF,
                miss="mesh resolution of the collapsing column",
            )
        )
    if len(runs) >= 3:
        hs = [r["h"] for r in runs]
        for key, label in (("front_vof", "front vs VOF"), ("height_vof", "height vs VOF")):
            res.rows.append(
                Row(
                    name,
                    f"mesh convergence, {label}",
                    "observed order over the three meshes (dt = 1 ms)",
                    observed_order(hs, [r[key] for r in runs]),
                    TOL_ORDER,
                    WHY_ORDER,
                    sense=">=",
                    miss="the error does not shrink steadily with the mesh: at "
                    "0.004 m it is comparable with the VOF reference's own "
                    "error and the digitisation",
                )
            )
    dt_runs = _dt_study(end, quick)
    base = dt_runs[-1]
    for r in dt_runs[:-1]:
        df, dh = _difference(r, base)
        for q, v in (("front", df), ("height", dh)):
            until = 0.2 if q == "front" else 0.4
            res.rows.append(
                Row(
                    "time step",
                    f"{q}, dt = {r['dt']:g} vs {base['dt']:g} s",
                    f"max |difference| / a, t <= {until} s, h = 0.008 m",
                    v,
                    TOL_DT[r["dt"]],
                    WHY_DT[r["dt"]],
                    miss="the largest difference is one output where the f = 1/2 "
                    "crossing of the thin surge tip (front, t ~ 0.19 s) or of "
                    "the thinning column (height, t ~ 0.38 s) jumps by part of "
                    "a cell (one cell is 0.07 a); the RMS differences are a "
                    "tenth of that and the errors against the data do not "
                    "change with dt (see the section)",
                )
            )
    _figure_ar2(out, runs, paper, dt_runs)
    res.figures.append(
        (
            "dam_break_ar2.png",
            "Aspect ratio 2: front and column height against "
            "the experiments and the VOF reference (left, middle); time-step "
            "independence at 0.008 m (right).",
        )
    )
    res.text = _text_ar2(runs, paper, dt_runs, tol_mm, tol_ko)
    return res


def _dt_study(end: float, quick: bool) -> list[Measures]:
    if quick:
        end = min(end, 0.4)
    return [_run_ar2(0.008, dt, end) for dt in DTS]


def _difference(r: Measures, base: Measures, rms: bool = False) -> list[float]:
    """Largest (or RMS) |r - base| / a of the front (t <= 0.2 s) and height (t <= 0.4 s)."""
    out = []
    for key, until in (("front", 0.2), ("height", 0.4)):
        sel = base["t"] <= until + 1e-9
        d = np.interp(base["t"][sel], r["t"], r[key]) - base[key][sel]
        out.append(float((np.sqrt(np.mean(d**2)) if rms else np.max(np.abs(d))) / A))
    return out


def _figure_ar2(
    out: Path, runs: list[Measures], paper: Measures | None, dt_runs: list[Measures]
) -> None:
    plt = pyplot()
    fig, ax = plt.subplots(1, 3, figsize=(15, 4.2))
    s2, s1 = math.sqrt(2 * G / A), math.sqrt(G / A)
    vof = load(VOF)
    for r in runs + ([paper] if paper else []):
        style = "--" if r is paper else "-"
        lab = f"MPM h = {r['h']} m, dt = {r['dt']:g} s"
        ax[0].plot(r["t"] * s2, r["front"] / A, style, label=lab)
        ax[1].plot(r["t"] * s1, r["height"] / (2 * A), style, label=lab)
    ax[0].plot(vof[:, 0] * s2, vof[:, 1] / A, "k:", label="VOF (interFoam, 0.004 m)")
    ax[1].plot(vof[:, 0] * s1, vof[:, 2] / (2 * A), "k:", label="VOF (interFoam, 0.004 m)")
    mm, ko, mmh = load(MM_FRONT), load(KO_FRONT), load(MM_HEIGHT)
    ax[0].plot(mm[:, 0], mm[:, 1], "ko", label="Martin & Moyce, Table 2")
    ax[0].plot(ko[:, 0], ko[:, 1], "ks", mfc="none", label="Koshizuka & Oka")
    ax[1].plot(mmh[:, 0], mmh[:, 1], "ko", label="Martin & Moyce, Table 6")
    ax[0].set(xlabel="T = t sqrt(2 g / a) [-]", ylabel="front x / a [-]", xlim=(0, 4), ylim=(1, 4))
    ax[1].set(xlabel="tau = t sqrt(g / a) [-]", ylabel="height eta / (2 a) [-]", xlim=(0, 6))
    for r in dt_runs:
        ax[2].plot(r["t"], r["front"] / A, label=f"front, dt = {r['dt']:g} s")
        ax[2].plot(r["t"], r["height"] / A, "--", label=f"height, dt = {r['dt']:g} s")
    ax[2].set(xlabel="t [s]", ylabel="x / a, eta / a [-]", title="h = 0.008 m")
    for a_ in ax:
        a_.legend(fontsize=7)
    fig.tight_layout()
    save(fig, out / "dam_break_ar2.png")


def _text_ar2(
    runs: list[Measures],
    paper: Measures | None,
    dt_runs: list[Measures],
    tol_mm: float,
    tol_ko: float,
) -> str:
    doc = __doc__.split("\n", 3)[3].strip()
    rows = [
        [
            r["h"],
            r["dt"],
            fmt(r["front_mm"]),
            fmt(r["front_ko"]),
            fmt(r["height_mm"]),
            fmt(r["front_vof"]),
            fmt(r["height_vof"]),
            r["particles"],
            r["lost"],
            r["inside"],
            fmt(r["mass"]),
            r["ppc"],
            fmt(r["wall"]),
        ]
        for r in runs + ([paper] if paper else [])
    ]
    table = markdown_table(
        [
            "h (m)",
            "dt (s)",
            "front vs M&M (a)",
            "front vs K&O (a)",
            "height vs M&M (a)",
            "front vs VOF (a)",
            "height vs VOF (a)",
            "particles",
            "lost",
            "put back inside",
            "mass change",
            "max particles per cell at the end",
            "wall (s)",
        ],
        rows,
    )
    base = dt_runs[-1]
    dt_rows = []
    for r in dt_runs[:-1]:
        df, dh = _difference(r, base)
        rf, rh = _difference(r, base, rms=True)
        dt_rows.append([f"{r['dt']:g} vs {base['dt']:g}", fmt(df), fmt(dh), fmt(rf), fmt(rh)])
    dt_table = markdown_table(
        [
            "dt pair (s)",
            "front, max diff. t <= 0.2 s (a)",
            "height, max diff. t <= 0.4 s (a)",
            "front, RMS diff. (a)",
            "height, RMS diff. (a)",
        ],
        dt_rows,
    )
    dt_table += "\n\n" + markdown_table(
        [
            "dt (s)",
            "front vs VOF (a)",
            "height vs VOF (a)",
            "height vs M&M (a)",
            "front vs M&M (a)",
        ],
        [
            [
                f"{r['dt']:g}",
                fmt(r["front_vof"]),
                fmt(r["height_vof"]),
                fmt(r["height_mm"]),
                fmt(r["front_mm"]),
            ]
            for r in dt_runs
        ],
    )
    return (
        doc + "\n\nThe experiment-front tolerances follow from the data: the VOF reference "
        f"is {tol_mm - EXTRA:.3f} a (RMS) from Martin & Moyce's Table 2 and "
        f"{tol_ko - EXTRA:.3f} a from Koshizuka & Oka over the same points.\n\n"
        + table
        + "\n\n**Time-step independence** (0.008 m, differences from the dt = 0.5 ms run):"
        "\n\n" + dt_table
    )
