"""Lobovsky et al. (2014), H = 0.3 m, in 2D: water levels and pressure on the downstream wall.

examples/lobovsky.toml: a column 0.6 m x 0.3 m at the left end of a tank 1.61 m long
(tank height 0.92 m, not given by the sources; it holds the run-up), released at once
(the experiment lifts a gate at about 3.5 m/s), 1.25 s (t sqrt(g/H) = 7.1), dt = 1 ms,
outputs every step. Times and values are compared in the data's units t sqrt(g/H), h/H and
p/(rho g H). The gauges and sensors are the example's ``[[probes]]`` (levels H1-H4,
pressures sensor_1-4 with ``estimate = "mean"``), read from the run's probes.

* **Water level** at a gauge x_g (a level probe with its foot on the floor): the height where the cell volume fraction profile,
  interpolated linearly in x between the two cell columns around x_g, first drops below
  1/2 going up from the floor: the top of the water layer on the floor (0 when dry).
  Splashes and drops above the layer are not counted (taking the highest f = 1/2 crossing
  instead puts single-sample spikes of up to 2.5 H into the series). Error: RMS of
  (h_sim - h_exp)/H over the measured samples up to the run's end. Where the data hold two repetitions (H2, H3, H4)
  the reference is their mean; their own RMS difference is the data's scatter.
* **Wall pressure** at a sensor at height y_s on the right wall (a pressure probe at
  (1.61 m, y_s), window one cell, estimate "mean"): the mean pressure of the
  particles in the last cell column (x > 1.61 m - h) within |y - y_s| <= h/2 (the window
  clipped at the floor; 0 when it holds no particle). The measured series (20 kHz) is
  averaged over 1 ms, the simulation's step, before the peak is taken. **Peak**: the
  largest value in the impact window 2 <= t sqrt(g/H) <= 3.5; errors: the time difference
  in t sqrt(g/H) and the relative difference of the peak value.

**The gate** (issue 44): the experiment releases the column by lifting a gate, which the
example replaces by an instant release. The case runs a second time with the gate: a box
GATE_WIDTH wide against the column's face (x = 0.6 m) and GATE_HEIGHT tall, lifted at
GATE_SPEED from t = 0 (the Altair nanoFluidX manual's figure for this experiment,
data/validation/README.md, section D; Lobovsky et al. do not tabulate the gate's path) until
its top reaches the tank's, a slip face as the walls are. Its rows are the same measures
with the same tolerances, named "gate: ...". How much of the surge's lead the instant
release explains is read from the surge's **arrival** at each sensor: the first time the
pressure (the experiment's 1 ms mean) exceeds ARRIVAL rho g H, shown for the experiment and
both runs.
"""

import math
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ..simulation import Simulation
from ..studies.reference_data import load
from .common import CaseResult, Row, fmt, markdown_table, pyplot, run_example, save
from .types import Context, FloatArray

if TYPE_CHECKING:
    from ..case import Case

H = 0.3  # m, column height
G = 9.81
LEVELS = "validation/lobovsky_2014_H300mm_water_levels_fig16.csv"
PRESSURE = "validation/lobovsky_2014_H300mm_wall_pressure_fig18_event5.csv"
# the example's [[probes]]: name -> x (m) and data columns; name -> y (m) and data column
GAUGES = {"H1": (0.300, [1]), "H2": (0.865, [2, 3]), "H3": (1.114, [4, 5]), "H4": (1.3625, [6, 7])}
SENSORS = {
    "sensor 1": (0.003, 1),
    "sensor 2": (0.015, 2),
    "sensor 3": (0.030, 4),
    "sensor 4": (0.080, 5),
}


def probe_name(label: str) -> str:
    """The probe of examples/lobovsky.toml behind a gauge's or sensor's label."""
    return label.replace(" ", "_")


IMPACT = (2.0, 3.5)  # window of the first impact peak, in t sqrt(g/H)
ARRIVAL = 0.1  # p / (rho g H) that marks the surge's arrival at a sensor
FACE = 0.6  # m: the column's downstream face in examples/lobovsky.toml
GATE_SPEED = 3.46  # m/s, upwards from t = 0
GATE_WIDTH = 0.02  # m: two cells of the report's mesh, so that nodes lie inside it
GATE_HEIGHT = 0.35  # m: over the column's 0.3 m
SPACING, SPACING_QUICK = 0.01, 0.01
END, END_QUICK = 1.25, 0.75  # s

# tolerances, fixed before the results were looked at
TOL_LEVEL = 0.10
WHY_LEVEL = (
    "0.1 H = 30 mm: the gauges see a bore and splashes whose repetitions differ by "
    "several cm, and the release is a gate, not instantaneous"
)
TOL_PEAK_TIME = 0.2
WHY_PEAK_TIME = (
    "0.2 in t sqrt(g/H) = 35 ms: the gate takes ~0.09 s to clear the column, which "
    "delays the experiment's surge"
)
TOL_PEAK = 0.5
WHY_PEAK = (
    "impact peaks scatter by about a factor of two between Lobovsky's 100 repetitions, "
    "and this series is one of them (peak event 5)"
)


def assert_probe(sim: Simulation, label: str, quantity: str, position: Sequence[float]) -> None:
    """The example's probe is where this module's table says (they are kept in step)."""
    probe = next(p for p in sim.case.probes if p.name == probe_name(label))
    if probe.quantity != quantity or not np.allclose(probe.position, position):
        raise RuntimeError(
            f"examples/lobovsky.toml: probe {probe.name} is a {probe.quantity} "
            f"probe at {probe.position} m; the validation expects a {quantity} "
            f"probe at {position} m"
        )


def _running_mean(y: FloatArray, n: int) -> FloatArray:
    if n <= 1:
        return y
    k = np.ones(n) / n
    return np.convolve(y, k, mode="same")


def _peak(t: FloatArray, p: FloatArray) -> tuple[float, float]:
    sel = (t >= IMPACT[0]) & (t <= IMPACT[1])
    if not np.any(sel):
        return float("nan"), float("nan")
    k = np.argmax(np.where(sel, p, -np.inf))
    return float(t[k]), float(p[k])


def gate_obstacle(case: "Case") -> str:
    """The override that adds the experiment's gate to examples/lobovsky.toml: a box against
    the column's face lifted at GATE_SPEED until its top reaches the tank's."""
    stop = (case.domain.size[1] - GATE_HEIGHT) / GATE_SPEED
    return (
        f"obstacles=[{{name='gate', type='box', min=[{FACE}, 0.0], "
        f"max=[{FACE + GATE_WIDTH}, {GATE_HEIGHT}], motion={{type='velocity', "
        f"velocity=[0.0, {GATE_SPEED}], stop={stop}}}}}]"
    )


def arrival(t: FloatArray, p: FloatArray) -> float:
    """The first time (in t's units) at which p (rho g H) exceeds ARRIVAL: the surge's
    arrival at a sensor (nan if it never does)."""
    above = np.flatnonzero(p > ARRIVAL)
    return float(t[above[0]]) if above.size else float("nan")


def run(out: Path, quick: bool = False, context: Context | None = None) -> CaseResult:
    h = SPACING_QUICK if quick else SPACING
    end = END_QUICK if quick else END
    res = CaseResult("lobovsky", "Lobovsky et al. (2014), H = 0.3 m")
    dt = 1e-3
    over = [f"grid.spacing={h}", f"time.dt={dt}", f"time.end={end}", f"output.interval={dt}"]
    instant = run_example("lobovsky.toml", over)
    gated = run_example("lobovsky.toml", [*over, gate_obstacle(instant.case)])
    runs = (("", instant, "C0", "instant release"), ("gate: ", gated, "C1", "gate"))
    scale = math.sqrt(G / H)
    lev = load(LEVELS)
    prs = load(PRESSURE)
    name = "Lobovsky"
    plt = pyplot()
    fig, ax = plt.subplots(2, 4, figsize=(16, 7))
    level_lines = []
    for k, (k_name, (xg, cols)) in enumerate(GAUGES.items()):
        a_ = ax[0, k]
        for c in cols:
            a_.plot(lev[:, 0], lev[:, c], "k-", lw=0.8, alpha=0.6)
        line: list[object] = [k_name, xg]
        for tag, sim, colour, label in runs:
            assert_probe(sim, k_name, "level", [xg, 0.0])
            ts = np.array(sim.series("time")) * scale
            level = np.array(sim.probe_series(probe_name(k_name))) / H
            sel = lev[:, 0] <= ts[-1] + 1e-9
            ref = lev[sel][:, cols].mean(axis=1)
            rms = float(np.sqrt(np.mean((np.interp(lev[sel, 0], ts, level) - ref) ** 2)))
            res.rows.append(
                Row(
                    name,
                    f"{tag}water level {k_name} (x = {xg} m)",
                    f"RMS (h - h_exp) / H, t sqrt(g/H) <= {ts[-1]:.2f}",
                    rms,
                    TOL_LEVEL,
                    WHY_LEVEL,
                    miss="after the impact the reflected jet plunges back over the "
                    "gauge: breaking and splashes that a 2D inviscid run at this "
                    "mesh does not reproduce sample by sample",
                )
            )
            line.append(fmt(rms))
            a_.plot(ts, level, f"{colour}-", label=f"MPM h = {h} m, {label}")
        sel = lev[:, 0] <= end * scale + 1e-9  # the repetitions over the run's span
        scatter = (
            float(np.sqrt(np.mean((lev[sel, cols[0]] - lev[sel, cols[1]]) ** 2)))
            if len(cols) == 2
            else float("nan")
        )
        level_lines.append([*line, fmt(scatter)])
        a_.set(
            title=f"{k_name}, x = {xg} m",
            xlabel="t sqrt(g/H) [-]",
            ylabel="h / H [-]",
            xlim=(0, max(end * scale, 1)),
        )
        a_.legend(fontsize=7)
    n_avg = max(1, int(round(dt * scale / np.median(np.diff(prs[:, 0])))))
    sensor_lines, arrival_lines = [], []
    for k, (s_name, (ys, col)) in enumerate(SENSORS.items()):
        pe = _running_mean(prs[:, col], n_avg)
        t_exp, p_exp = _peak(prs[:, 0], pe)
        a_exp = arrival(prs[:, 0], pe)
        a_ = ax[1, k]
        a_.plot(prs[:, 0], prs[:, col], "-", color="0.7", lw=0.5, label="experiment, 20 kHz")
        a_.plot(prs[:, 0], pe, "k-", lw=0.8, label="experiment, 1 ms mean")
        times: list[object] = [fmt(t_exp)]
        peaks: list[object] = [fmt(p_exp)]
        arrivals: list[object] = [s_name, ys * 1e3, fmt(a_exp)]
        for tag, sim, colour, label in runs:
            assert_probe(sim, s_name, "pressure", [sim.case.domain.size[0], ys])
            rho = sim.case.material.density
            ts = np.array(sim.series("time")) * scale
            ps = np.array(sim.probe_series(probe_name(s_name))) / (rho * G * H)
            t_sim, p_sim = _peak(ts, ps)
            rel = (p_sim - p_exp) / p_exp
            res.rows.append(
                Row(
                    name,
                    f"{tag}peak time, {s_name} (y = {ys * 1e3:g} mm)",
                    "|t_sim - t_exp| sqrt(g/H)",
                    abs(t_sim - t_exp),
                    TOL_PEAK_TIME,
                    WHY_PEAK_TIME,
                    miss=(
                        "the measured series has no sharp impact peak in the window at "
                        "80 mm (its maximum lies at the window's end), so the peak's time "
                        "is that of whichever bump of the run-up is highest"
                        if s_name == "sensor 4"
                        else "an instantaneous release: the simulated surge arrives before "
                        "the experiment's, whose gate still holds the water back"
                        if not tag
                        else f"the gate's lift ({GATE_SPEED} m/s, the manual's figure, not "
                        "a measured path) sets when the surge leaves"
                    ),
                )
            )
            res.rows.append(
                Row(
                    name,
                    f"{tag}peak pressure, {s_name} (y = {ys * 1e3:g} mm)",
                    "(p_sim - p_exp) / p_exp of the impact peak (signed)",
                    rel,
                    TOL_PEAK,
                    WHY_PEAK,
                    sense="|<=|",
                    miss="impact peaks last a few ms: the 1 ms step and the "
                    "h-wide sensor window set the simulated value; at 80 mm "
                    "the measured series has no sharp impact peak in the window "
                    "(its maximum lies at the window's end), and the run "
                    + ("overshoots" if rel > 0 else "falls short of")
                    + " the 1 ms mean of the run-up pressure there: its sheet runs up the "
                    "wall at p = 0, a wall being unable to pull (docs/method.md, item 2)",
                )
            )
            times.append(fmt(t_sim))
            peaks.append(fmt(p_sim))
            a_sim = arrival(ts, ps)
            arrivals += [fmt(a_sim), f"{a_sim - a_exp:+.3f}"]
            a_.plot(ts, ps, f"{colour}-", label=f"MPM h = {h} m, {label}")
        sensor_lines.append([s_name, ys * 1e3, *times, *peaks, fmt(float(prs[:, col].max()))])
        arrival_lines.append(arrivals)
        a_.set(
            title=f"{s_name}, y = {ys * 1e3:g} mm",
            xlabel="t sqrt(g/H) [-]",
            ylabel="p / (rho g H) [-]",
            xlim=(1.5, max(end * scale, 2)),
        )
        a_.legend(fontsize=7)
    fig.tight_layout()
    save(fig, out / "lobovsky.png")
    res.figures.append(
        (
            "lobovsky.png",
            "Water levels at H1-H4 (top; black: the measured repetitions) and pressure on "
            "the downstream wall (bottom), the column released at once (C0) and by the "
            "experiment's gate (C1).",
        )
    )
    walls = ", ".join(f"{sim.summary['wall_seconds']:.0f} s" for _, sim, _, _ in runs)
    res.text = (
        __doc__.split("\n", 2)[2].strip() + f"\n\nGrid spacing {h} m "
        f"({instant.particles.count} particles; wall {walls}, instant and gated). The gate: "
        f"{GATE_WIDTH} m wide, {GATE_HEIGHT} m tall, lifted at {GATE_SPEED} m/s; it clears "
        f"the column's 0.3 m after {H / GATE_SPEED:.3f} s (t sqrt(g/H) = "
        f"{H / GATE_SPEED * scale:.2f}).\n\n"
        + markdown_table(
            [
                "gauge",
                "x (m)",
                "RMS error / H, instant",
                "RMS error / H, gate",
                "scatter of the two repetitions / H",
            ],
            level_lines,
        )
        + "\n\n"
        + markdown_table(
            [
                "sensor",
                "y (mm)",
                "peak time, exp. (t sqrt(g/H))",
                "peak time, instant",
                "peak time, gate",
                "peak p/(rho g H), exp. (1 ms mean)",
                "peak, instant",
                "peak, gate",
                "raw 20 kHz maximum, exp.",
            ],
            sensor_lines,
        )
        + f"\n\nThe surge's arrival (the first p > {ARRIVAL} rho g H; t sqrt(g/H), and "
        "the run's lead (-) or lag (+) on the experiment):\n\n"
        + markdown_table(
            [
                "sensor",
                "y (mm)",
                "exp. (1 ms mean)",
                "instant",
                "instant - exp.",
                "gate",
                "gate - exp.",
            ],
            arrival_lines,
        )
    )
    return res
