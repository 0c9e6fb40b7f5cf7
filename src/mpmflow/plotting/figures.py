"""``mpmflow plot DIR``: figures of a run's outputs (matplotlib, PNG and an animated GIF).

Reads ``timeseries.csv``, ``probes.csv``, ``summary.json`` and the snapshots listed in ``particles.pvd``;
writes into the plot folder:

- ``timeseries.png``   front and column height, energies, largest speed and pressure,
                       pressure noise and wetted volume ratio against time;
- ``probes.png``       (with probes) the probes' series, one panel per quantity (pressures
                       in Pa, levels in m), each over the measured series the case names
                       (``probes.N.data``), drawn dashed in the probe's colour; over
                       LEGEND_MAX probes on a panel, coloured by position, no legend;
- ``snapshots/particles_NNNNNN.png``   each snapshot, particles coloured by pressure;
- ``snapshots.png``    up to six snapshots side by side (an overview);
- ``animation.gif``    the snapshots as an animation (matplotlib's PillowWriter);
- in 3D, beside each slice: ``snapshots/surface_NNNNNN.png`` the water's surface (the
  particles' volume fraction on the grid at 1/2, by marching cubes) and the obstacles in
  a 3D view, and ``surfaces.png`` the overview's snapshots so (``plotting.surface``;
  separate files, as the 3D box wants another shape of figure than the slice's plane).
  Without scikit-image they are left out with a note.
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from types import ModuleType
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from ..errors import CaseError
from ..geometry.rotation import quaternion_matrix
from ..grid import Grid
from ..output import check_out_dir
from ..results import Snapshot, open_run
from .mpl import pyplot, save

if TYPE_CHECKING:  # matplotlib is an optional extra: imported when a figure is made
    from matplotlib.axes import Axes
    from matplotlib.collections import PathCollection

DPI = 80

# The types of a run's outputs as mpmflow.results reads them: a CSV's columns by name, and
# summary.json (parsed JSON: Any for its values, whose shape the code reads key by key).
# ``plt`` arguments are matplotlib.pyplot (``mpl.pyplot``), a module.
Columns = Mapping[str, NDArray[np.float64]]
Summary = Mapping[str, Any]
Floats = NDArray[np.float64]


def energy_changes(series: Columns) -> tuple[Floats, Floats]:
    """(potential - initial, total - initial) of a run's timeseries, total = kinetic +
    potential energy of the particles and the free bodies, each the change since the first
    row. The initial total holds the initial kinetic energy too: a body released with a
    velocity starts with it, and subtracting only the initial potential energy started "total
    - initial" at the initial kinetic energy (+0.26 J for stl_drop_3d's blob at 1 m/s) as if
    energy had been made."""
    potential = series["potential_energy"]
    total = series["kinetic_energy"] + potential
    if "body_energy" in series:  # the free bodies' KE + PE (runs before 2026-12-01: none)
        total = total + series["body_energy"]
    return potential - potential[0], total - total[0]


def energy_label(summary: Summary) -> str:
    """The energy axis' label: per metre of depth in 2D (J/m), absolute in 3D (J), as the
    summary's units say. A run still going has no summary yet, and timeseries.csv does not
    say its dimension: the label then gives both rather than guess one."""
    unit = summary.get("units", {}).get("kinetic_energy")
    return f"energy [{unit}]" if unit else "energy [J/m in 2D, J in 3D]"


def plot_timeseries(series: Columns, summary: Summary, path: Path, plt: ModuleType) -> None:
    t = series["time"]
    fig, ax = plt.subplots(2, 2, figsize=(10, 7), sharex=True)
    ax[0, 0].plot(t, series["front"], label="surge front")
    ax[0, 0].plot(t, series["height"], label="column height")
    ax[0, 0].set_ylabel("m")
    potential, total = energy_changes(series)
    ax[0, 1].plot(t, series["kinetic_energy"], label="kinetic")
    ax[0, 1].plot(t, potential, label="potential - initial")
    ax[0, 1].plot(t, total, "k--", label="total - initial")
    ax[0, 1].set_ylabel(energy_label(summary))
    ax[1, 0].plot(t, series["max_speed"], label="largest particle speed [m/s]")
    right = ax[1, 0].twinx()
    right.plot(t, series["max_pressure"], "C3", label="largest pressure [Pa]")
    right.set_ylabel("Pa", color="C3")
    ax[1, 0].set_ylabel("m/s")
    ax[1, 1].plot(t, series["pressure_noise"], label="pressure noise [Pa]")
    ax[1, 1].set_ylabel("Pa")
    vol = ax[1, 1].twinx()
    vol.plot(t, series["volume_ratio"], "C2", label="wetted volume ratio [-]")
    vol.set_ylabel("volume ratio", color="C2")
    for a, extra in ((ax[0, 0], None), (ax[0, 1], None), (ax[1, 0], right), (ax[1, 1], vol)):
        handles, labels = a.get_legend_handles_labels()
        if extra is not None:
            h2, l2 = extra.get_legend_handles_labels()
            handles, labels = handles + h2, labels + l2
        a.legend(handles, labels, fontsize=8, loc="best")
        a.grid(alpha=0.3)
    for a in ax[1]:
        a.set_xlabel("time [s]")
    fig.suptitle(summary.get("case", {}).get("title") or "mpmflow run", fontsize=10)
    fig.tight_layout()
    save(fig, path, DPI)


QUANTITY = {"Pa": ("pressure", "pressure [Pa]"), "m": ("level", "water level [m]")}


def measured_series(data: Mapping[str, str]) -> tuple[Floats, Floats]:
    """(time, values) of a probe's measured series, ``probes.N.data`` as the resolved case
    holds it ({"path", "column", "time_column"}), checked as the case's loading checks it
    (``case.probe_data``); CaseError when the file cannot be read or no longer holds it."""
    from ..case.probe_data import read_series

    try:
        return read_series(data["path"], data["time_column"], data["column"])
    except ValueError as err:
        raise CaseError(str(err)) from None


# probes a panel names in a legend: while each has its own colour of matplotlib's cycle
LEGEND_MAX = 10


def plot_probes(
    probes: Columns,
    summary: Summary,
    units: Mapping[str, str | None],
    path: Path,
    plt: ModuleType,
    notes: list[str],
) -> None:
    """probes.png: one panel per quantity, each probe's series and its measured series.
    Up to LEGEND_MAX probes on a panel are named in its legend; more are coloured by
    position (``_lines_by_position``). ``probes``: probes.csv's columns; ``units``:
    {probe: "Pa" | "m"}."""
    t = probes["time"]
    names = [n for n in probes if n != "time"]
    data = {p.get("name"): p.get("data") for p in summary.get("case", {}).get("probes", [])}
    panels = [u for u in QUANTITY if any(units.get(n) == u for n in names)]
    fig, axes = plt.subplots(
        len(panels), 1, figsize=(10, 3.2 * len(panels) + 0.6), sharex=True, squeeze=False
    )
    for ax, unit in zip(axes[:, 0], panels):
        group = [n for n in names if units.get(n) == unit]
        if len(group) <= LEGEND_MAX:
            colours = [
                ax.plot(t, probes[n], color=f"C{k}", label=n)[0].get_color()
                for k, n in enumerate(group)
            ]
        else:
            colours = _lines_by_position(ax, t, probes, group, summary, plt)
        measured = False
        for name, colour in zip(group, colours):
            ref = data.get(name)
            if ref:
                try:
                    te, ve = measured_series(ref)
                except CaseError as err:
                    notes.append(f"{err}; probes.png shows {name} without it.")
                    continue
                measured = True
                ax.plot(
                    te,
                    ve,
                    "--",
                    color=colour,
                    lw=0.8,
                    alpha=0.8,
                    label=f"{name}, measured ({ref['column']})",
                )
        ax.set_ylabel(QUANTITY[unit][1])
        if len(group) <= LEGEND_MAX:
            ax.legend(fontsize=7, loc="best", ncol=2)
        elif measured:  # the line styles only: a probe is told by its colour
            from matplotlib.lines import Line2D

            ax.legend(
                [Line2D([], [], color="0.3"), Line2D([], [], color="0.3", ls="--")],
                ["simulated", "measured"],
                fontsize=7,
                loc="upper right",
            )
        ax.grid(alpha=0.3)
        ax.set_xlim(t[0] if len(t) else 0.0, t[-1] if len(t) > 1 else 1.0)
    axes[-1, 0].set_xlabel("time [s]")
    fig.suptitle((summary.get("case", {}).get("title") or "mpmflow run") + ": probes", fontsize=10)
    fig.tight_layout()
    save(fig, path, DPI)


def probe_positions(summary: Summary) -> dict[str, list[float] | None]:
    """{probe: position (m)} as summary.json records them ({} while a run has none)."""
    return {name: p.get("position") for name, p in summary.get("probes", {}).items()}


def _lines_by_position(
    ax: Axes, t: Floats, probes: Columns, group: Sequence[str], summary: Summary, plt: ModuleType
) -> list[tuple[float, float, float, float] | Floats]:  # RGBA by Colormap
    """More probes than a legend can tell apart on one panel: one thin line each, all in
    one LineCollection (2,000 Line2D and their legend took 10 to 18 s to draw, and the
    legend overflowed the figure), coloured by the probe's position along the axis in which
    the panel's probes lie furthest apart, with a colour bar of that coordinate. Without
    the positions (a run still going has no summary.json) the colour is the probe's column
    in probes.csv, and the colour bar says so. Returns each probe's colour."""
    from matplotlib.collections import LineCollection

    where = probe_positions(summary)
    found = [where.get(n) for n in group]
    positions = [p for p in found if p is not None]
    if len(positions) == len(found) and len({len(p) for p in positions}) == 1:
        xyz = np.asarray(positions, dtype=float)
        axis = int(np.argmax(np.ptp(xyz, axis=0)))
        value, label = xyz[:, axis], f"probe's {'xyz'[axis]} [m]"
    else:
        value, label = np.arange(1.0, len(group) + 1), "probe's column in probes.csv"
    lines = LineCollection(
        [np.column_stack([t, probes[n]]) for n in group], cmap="viridis", linewidths=0.6
    )
    lines.set_array(value)
    ax.add_collection(lines)
    ax.autoscale_view()
    ax.set_title(
        f"{len(group)} probes, coloured by position"
        if label.endswith("[m]")
        else f"{len(group)} probes",
        fontsize=8,
    )
    plt.colorbar(lines, ax=ax, label=label, pad=0.01)
    return [lines.cmap(lines.norm(v)) for v in value]


def side_view(
    x: Floats, p: Floats, size: Sequence[float] | Floats, spacing: float
) -> tuple[Floats, Floats, list[float], tuple[str, str], str]:
    """What a snapshot figure shows: in 2D the particles on the x-y plane; in 3D the slice
    one grid cell thick through the middle of the width (y), on the x-z plane (z up).
    Returns (points, pressures, the plane's extent, axis names, a caption)."""
    if len(size) < 3:
        return x[:, :2], p, list(size[:2]), ("x", "y"), ""
    mid = 0.5 * size[1]
    keep = np.abs(x[:, 1] - mid) <= 0.5 * spacing
    return (
        x[keep][:, [0, 2]],
        p[keep],
        [size[0], size[2]],
        ("x", "z"),
        f"slice y = {mid:.4g} m +- {0.5 * spacing:.3g} m",
    )


def obstacle_section(
    summary: Summary,
    plane: Sequence[float],
    notes: list[str],
    t: float | None = None,
    poses: dict[str, Floats] | None = None,
) -> tuple[Floats, Floats, Floats] | None:
    """The obstacles on the figures' plane (the x-y plane in 2D, the mid-width x-z slice in
    3D) as (X, Y, signed distance) on a fine raster, or None without obstacles. Rebuilt from
    the case in summary.json; an obstacle that cannot be rebuilt (a mesh file moved away) is
    left out with a note. A moving obstacle (obstacles.N.motion) is drawn where bodies.csv
    (``poses``: its columns) puts it at time ``t`` (its pose interpolated between the rows),
    where it started without them."""
    from ..case import validate_case

    spec = summary.get("case", {})
    if not spec.get("obstacles"):
        return None
    try:
        case = validate_case(spec)
        solids = [case.obstacle_shape(k) for k in range(len(case.obstacles))]
    except CaseError as err:
        notes.append(f"the obstacles cannot be drawn: {err}")
        return None
    n = 400
    X, Y = np.meshgrid(
        np.linspace(0, plane[0], n), np.linspace(0, plane[1], max(2, int(n * plane[1] / plane[0])))
    )
    if len(case.domain.size) == 2:
        pts = np.column_stack([X.ravel(), Y.ravel()])
    else:
        mid = 0.5 * summary.get("grid", {}).get("domain_used", case.domain.size)[1]
        pts = np.column_stack([X.ravel(), np.full(X.size, mid), Y.ravel()])
    phis = []
    for k, solid in enumerate(solids):
        moving = case.obstacles[k].motion is not None and poses is not None and t is not None
        name = case.obstacles[k].name or f"obstacle{k}"
        at = _at_start(pts, poses, name, float(t)) if moving else pts  # type: ignore[arg-type]
        phis.append(solid.signed_distance(at))
    phi = np.min(phis, axis=0).reshape(X.shape)
    return X, Y, phi


def _poses(run_dir: Path, notes: list[str]) -> dict[str, Floats] | None:
    """bodies.csv's columns (the moving obstacles' poses), or None without the file."""
    from ..output.timeseries import read_table

    path = run_dir / "bodies.csv"
    if not path.is_file():
        return None
    try:
        table, read_notes = read_table(path)
    except CaseError as err:
        notes.append(f"the moving obstacles are drawn where they started: {err}")
        return None
    notes.extend(read_notes)
    return {k: np.asarray(v, dtype=float) for k, v in table.items()}


def _at_start(pts: Floats, poses: dict[str, Floats], name: str, t: float) -> Floats:
    """The points ``pts`` (n, D) carried back from a moving obstacle's pose at time t to where
    it started (bodies.csv's first row, at t = 0), where its shape is defined: x0 = R(t)^T (x
    - c(t)) + c(0). Unchanged without its columns."""
    D = pts.shape[1]
    axes = "xyz"[:D]
    time = poses.get("time")
    if time is None or time.size == 0 or time[0] != 0.0 or f"{name}_x" not in poses:
        return pts
    c = np.array([np.interp(t, time, poses[f"{name}_{a}"]) for a in axes])
    c0 = np.array([poses[f"{name}_{a}"][0] for a in axes])
    if D == 2:
        angle = np.radians(np.interp(t, time, poses[f"{name}_angle"]))
        R = np.array([[np.cos(angle), -np.sin(angle)], [np.sin(angle), np.cos(angle)]])
    else:
        R = quaternion_matrix(*(float(np.interp(t, time, poses[f"{name}_q{q}"])) for q in "wxyz"))
    moved: Floats = (pts - c) @ R + c0
    return moved


def _draw(
    ax: Axes,
    xy: Floats,
    p: Floats,
    t: float,
    size: Sequence[float],
    vmax: float,
    plt: ModuleType,
    solid: tuple[Floats, Floats, Floats] | None = None,
) -> PathCollection:
    if solid is not None and (solid[2] < 0).any():
        ax.contourf(
            solid[0], solid[1], solid[2], levels=[solid[2].min() - 1.0, 0.0], colors=["0.55"]
        )
    art = ax.scatter(
        xy[:, 0],
        xy[:, 1],
        c=p,
        s=1.0,
        marker="s",
        cmap="viridis",
        vmin=0.0,
        vmax=vmax,
        linewidths=0,
        rasterized=True,
    )
    ax.set_xlim(0, size[0])
    ax.set_ylim(0, size[1])
    ax.set_aspect("equal")
    ax.set_title(f"t = {t:.3f} s", fontsize=9)
    ax.tick_params(labelsize=7)
    return art


def _name_axes(ax: Axes, names: Sequence[str], caption: str = "", y: bool = True) -> None:
    """The plane's axes named with their unit; in 3D the x label says which slice it is
    (an overview passes it to its title instead, its panels being too narrow for it)."""
    ax.set_xlabel(f"{names[0]} [m]" + (f" ({caption})" if caption else ""))
    if y:
        ax.set_ylabel(f"{names[1]} [m]")


def plot_snapshots(
    snaps: Sequence[Snapshot],
    summary: Summary,
    folder: Path,
    plt: ModuleType,
    notes: list[str],
    run_dir: Path | None = None,
) -> list[Path]:
    """One PNG per snapshot, an overview of up to six, and the GIF; returns the paths.
    Snapshots that cannot be read (missing, damaged) are left out with a note."""
    from matplotlib.animation import PillowWriter

    data, readable, solid3d = [], [], []
    for snap in snaps:
        try:
            d = snap.read()
        except CaseError as err:
            notes.append(f"{err} It is left out of the figures.")
            continue
        data.append((snap.time, d["x"], d["pressure"]))
        readable.append((snap.time, snap.path))
        if d["x"].shape[1] == 3:
            solid3d.append((snap.time, snap.path, _water(d, summary)))
    if not readable:
        return []
    size = summary.get("grid", {}).get("domain_used")
    if size is None:
        size = np.max([xy.max(axis=0) for _, xy, _ in data], axis=0)
        size = size[:2] if not np.any([xy[:, 2:].any() for _, xy, _ in data]) else size
    spacing = summary.get("grid", {}).get("spacing") or float(np.max(size)) / 20
    caption = ""
    for k, (t, x, p) in enumerate(data):
        xy, pv, plane, names, caption = side_view(x, p, size, spacing)
        data[k] = (t, xy, pv)
    size = plane
    poses = _poses(run_dir, notes) if run_dir is not None else None
    moving = poses is not None and any(
        o.get("motion") for o in summary.get("case", {}).get("obstacles", [])
    )
    solid = obstacle_section(summary, plane, notes)
    # the colour scale: the 99.5th percentile over all snapshots, so that a few impact peaks
    # do not leave the rest of the run dark
    vmax = float(np.percentile(np.concatenate([p for _, _, p in data]), 99.5)) or 1.0
    (folder / "snapshots").mkdir(exist_ok=True)
    written = []
    sections = [
        obstacle_section(summary, plane, notes, t, poses) if moving else solid for t, _, _ in data
    ]
    for (t, xy, p), (_, f), section in zip(data, readable, sections):
        fig, ax = plt.subplots(figsize=(5, 5 * size[1] / size[0] + 0.6))
        art = _draw(ax, xy, p, t, size, vmax, plt, section)
        fig.colorbar(art, ax=ax, label="pressure [Pa]")
        _name_axes(ax, names, caption)
        out = folder / "snapshots" / (Path(f).stem + ".png")
        save(fig, out, DPI)
        written.append(out)
    pick = overview(len(data))
    fig, axes = plt.subplots(
        1, len(pick), figsize=(2.2 * len(pick) + 1.2, 2.8), squeeze=False, layout="constrained"
    )
    for j, (ax, k) in enumerate(zip(axes[0], pick)):
        art = _draw(ax, data[k][1], data[k][2], data[k][0], size, vmax, plt, sections[k])
        _name_axes(ax, names, y=j == 0)
    fig.colorbar(art, ax=axes[0].tolist(), label="pressure [Pa]")
    if caption:
        fig.suptitle(caption, fontsize=9)
    save(fig, folder / "snapshots.png", DPI)
    written.append(folder / "snapshots.png")
    fig, ax = plt.subplots(figsize=(5, 5 * size[1] / size[0] + 0.6))
    art = _draw(ax, data[0][1], data[0][2], data[0][0], size, vmax, plt, solid)
    fig.colorbar(art, ax=ax, label="pressure [Pa]")
    _name_axes(ax, names, caption)
    writer = PillowWriter(fps=4)
    tmp = folder / ".animation.partial.gif"  # Pillow picks the format from the suffix
    try:
        with writer.saving(fig, str(tmp), dpi=60):
            for t, xy, p in data:
                art.set_offsets(xy)
                art.set_array(p)
                ax.set_title(f"t = {t:.3f} s", fontsize=9)
                writer.grab_frame()
        os.replace(tmp, folder / "animation.gif")
    finally:
        tmp.unlink(missing_ok=True)
        plt.close(fig)
    written.append(folder / "animation.gif")
    if solid3d:
        written += plot_surfaces(solid3d, summary, folder, plt, notes)
    return written


def overview(n: int) -> NDArray[np.int64]:
    """Which of n snapshots an overview shows: up to six, evenly spread, first and last."""
    return np.unique(np.linspace(0, n - 1, min(6, n)).round().astype(int))


def _water(d: Mapping[str, Floats], summary: Summary) -> Floats:
    """The volume fraction field [cx, cy, cz] of one 3D snapshot's particles (``surface``):
    their volume is mass / material.density."""
    from .surface import volume_fraction

    grid = summary.get("grid", {})
    cells = grid.get("cells") or Grid.covering(grid["domain_used"], grid["spacing"]).cells
    density = summary.get("case", {}).get("material", {}).get("density", 1000.0)
    return volume_fraction(d["x"], d["mass"] / density, grid["spacing"], cells)


def plot_surfaces(
    fields: Sequence[tuple[float, Path, Floats]],
    summary: Summary,
    folder: Path,
    plt: ModuleType,
    notes: list[str],
) -> list[Path]:
    """The 3D pictures (``plotting.surface``): snapshots/surface_NNNNNN.png for each snapshot
    (beside its slice particles_NNNNNN.png) and surfaces.png, the overview's snapshots side
    by side. ``fields``: [(time, snapshot file, volume fraction field)]. Returns the
    paths."""
    from .surface import draw_surface, need_skimage, obstacle_triangles, water_surface

    try:
        need_skimage()
    except CaseError as err:
        notes.append(f"{err} The 3D pictures are left out.")
        return []
    grid = summary["grid"]
    size, spacing = grid["domain_used"], grid["spacing"]
    solids = obstacle_triangles(summary, notes)
    surfaces = [(t, f, *water_surface(field, spacing)) for t, f, field in fields]
    width = 6.0
    height = width * 0.75
    written = []
    for t, f, verts, faces in surfaces:
        fig = plt.figure(figsize=(width, height))
        ax = fig.add_subplot(projection="3d")
        draw_surface(ax, verts, faces, solids, size, f"t = {t:.3f} s")
        fig.subplots_adjust(0, 0, 1, 1)
        out = folder / "snapshots" / (Path(f).stem.replace("particles", "surface", 1) + ".png")
        save(fig, out, DPI)
        written.append(out)
    pick = overview(len(surfaces))
    cols = min(3, len(pick))  # up to three a row: a 3D box wants the width
    rows = -(-len(pick) // cols)
    fig = plt.figure(figsize=(4.4 * cols, 3.0 * rows + 0.3))
    for j, k in enumerate(pick):
        t, _, verts, faces = surfaces[k]
        ax = fig.add_subplot(rows, cols, j + 1, projection="3d")
        draw_surface(ax, verts, faces, solids, size, f"t = {t:.3f} s")
    fig.suptitle("water surface (volume fraction 1/2)", fontsize=9, y=0.995)
    fig.subplots_adjust(0, 0.03, 1, 1 - 0.4 / (3.0 * rows + 0.3), wspace=0.05, hspace=0.1)
    save(fig, folder / "surfaces.png", DPI)
    written.append(folder / "surfaces.png")
    return written


def plot_run(
    run_dir: str | Path, out_dir: str | Path | None = None, notes: list[str] | None = None
) -> list[Path]:
    """All figures of the run in ``run_dir`` (into ``out_dir``, default run_dir/plots);
    returns their paths. What could not be read is left out and said in ``notes`` (a list
    to append to)."""
    notes = notes if notes is not None else []
    plt = pyplot("mpmflow plot")
    run = open_run(run_dir)
    notes += run.notes
    if len(run.timeseries["time"]) == 0:
        raise CaseError(
            f"{run.folder}/timeseries.csv holds no rows yet (the run has not "
            "written its first output, or was stopped before it); nothing to "
            "plot."
        )
    out = Path(out_dir) if out_dir is not None else Path(run_dir) / "plots"
    check_out_dir(out_dir if out_dir is not None else out)  # (--out "" is refused)
    plot_timeseries(run.timeseries, run.summary, out / "timeseries.png", plt)
    written = [out / "timeseries.png"]
    units = run.units
    if len(run.probes) > 1 and len(run.probes["time"]):
        if any(units.get(n) in QUANTITY for n in run.probes if n != "time"):
            plot_probes(run.probes, run.summary, units, out / "probes.png", plt, notes)
            written.append(out / "probes.png")
    return [*written, *plot_snapshots(run.snapshots, run.summary, out, plt, notes, Path(run_dir))]
