"""`mpmflow plot`: time-series plots, particle snapshots and the animation of a run."""

import shutil

import pytest
from conftest import EXAMPLES
from PIL import Image

from mpmflow.cli import main


@pytest.mark.slow
def test_plot_makes_the_figures_and_the_animation(tmp_path, capsys):
    run = tmp_path / "run"
    assert (
        main(
            [
                "run",
                str(EXAMPLES / "dam_break.toml"),
                "--out",
                str(run),
                "-q",
                "--set",
                "grid.spacing=0.0114",
                "--set",
                "time.dt=0.01",
                "--set",
                "time.end=0.3",
                "--set",
                "output.snapshot_interval=0.1",
            ]
        )
        == 0
    )
    assert main(["plot", str(run)]) == 0
    plots = run / "plots"
    names = [
        "timeseries.png",
        "snapshots.png",
        "animation.gif",
        *(f"snapshots/particles_{k:06d}.png" for k in range(4)),
    ]
    for name in names:
        assert (plots / name).stat().st_size > 1000, name
    with Image.open(plots / "timeseries.png") as im:
        assert im.format == "PNG" and im.size == (800, 560)
    with Image.open(plots / "animation.gif") as im:
        assert im.format == "GIF" and im.n_frames == 4  # t = 0, 0.1, 0.2, 0.3 s
    assert not list(plots.glob(".*"))  # no temporary files left


def test_plot_of_a_folder_without_a_run(tmp_path, capsys):
    assert main(["plot", str(tmp_path)]) == 2
    assert "holds no timeseries.csv" in capsys.readouterr().err


@pytest.fixture(scope="module")
def small_run(tmp_path_factory):
    run = tmp_path_factory.mktemp("plot") / "run"
    assert (
        main(
            [
                "run",
                str(EXAMPLES / "dam_break.toml"),
                "--out",
                str(run),
                "-q",
                "--set",
                "grid.spacing=0.02",
                "--set",
                "time.dt=0.01",
                "--set",
                "time.end=0.2",
                "--set",
                "output.snapshot_interval=0.1",
            ]
        )
        == 0
    )
    return run


def _copy(run, tmp_path):
    out = tmp_path / "run"
    shutil.copytree(run, out, ignore=shutil.ignore_patterns(".mpmflow.lock", "plots"))
    return out


@pytest.mark.parametrize(
    "content, words",
    [
        (b"lorem ipsum dolor sit amet\nconsectetur\n", "is not an mpmflow table"),
        (bytes(range(256)) * 8, "is not a text file (it holds binary data)"),
        (b"time,front,height\n", "holds no rows yet"),
        (b"time,front,height\n0,0.1,0.2\n0.1,zz,0.2\n", "line 3, is damaged"),
        (b"", "is not an mpmflow table"),
    ],
)
def test_plot_of_a_damaged_time_series_is_one_clear_error(
    small_run, tmp_path, capsys, content, words
):
    """A garbage, binary, empty or header-only timeseries.csv raised a traceback."""
    run = _copy(small_run, tmp_path)
    (run / "timeseries.csv").write_bytes(content)
    capsys.readouterr()
    assert main(["plot", str(run)]) == 2
    err = capsys.readouterr().err
    assert words in err and "Traceback" not in err and err.count("\n") == 1, err


@pytest.mark.parametrize(
    "damage, words",
    [
        ("missing", "is missing: the index particles.pvd lists it"),
        ("truncated", "cannot be read"),
        ("garbage", "cannot be read"),
    ],
)
@pytest.mark.slow
def test_plot_leaves_out_a_missing_or_damaged_snapshot_with_a_note(
    small_run, tmp_path, capsys, damage, words
):
    """A missing VTU raised a traceback, a truncated one exit 1: the others are plotted
    and the note names the file."""
    run = _copy(small_run, tmp_path)
    vtu = run / "particles_000001.vtu"
    data = vtu.read_bytes()
    if damage == "missing":
        vtu.unlink()
    else:
        vtu.write_bytes(data[: len(data) // 2] if damage == "truncated" else b"\x00junk" * 99)
    capsys.readouterr()
    assert main(["plot", str(run)]) == 0
    err = capsys.readouterr().err
    assert "Traceback" not in err
    assert f"note: snapshot {vtu} (t = 0.1 s) {words}" in err, err
    assert "It is left out of the figures." in err
    pngs = sorted(p.name for p in (run / "plots" / "snapshots").glob("*.png"))
    assert pngs == ["particles_000000.png", "particles_000002.png"]
    with Image.open(run / "plots" / "animation.gif") as im:
        assert im.n_frames == 2


def test_plot_of_a_run_whose_snapshots_are_all_gone(small_run, tmp_path, capsys):
    run = _copy(small_run, tmp_path)
    for vtu in run.glob("particles_*.vtu"):
        vtu.unlink()
    assert main(["plot", str(run)]) == 0
    err = capsys.readouterr().err
    assert err.count("is missing") == 3 and "wrote 1 figures" in err
    assert (run / "plots" / "timeseries.png").is_file()


def _figures(monkeypatch):
    """{file name: figure} of what the plots save (the files are written as usual)."""
    from mpmflow.plotting import figures as plots

    saved, save = {}, plots.save

    def record(fig, path, dpi):
        saved[path.name] = fig
        save(fig, path, dpi)

    monkeypatch.setattr(plots, "save", record)
    return saved


def _panels(fig):
    return [ax for ax in fig.axes if ax.get_label() != "<colorbar>"]


@pytest.mark.slow
def test_snapshot_overview_names_its_axes_with_units(small_run, tmp_path, monkeypatch):
    """snapshots.png had no axis labels: each panel names x in m, the first y in m (the
    panels share the plane), and the colour bar is the pressure in Pa."""
    saved = _figures(monkeypatch)
    assert main(["plot", str(_copy(small_run, tmp_path))]) == 0
    fig = saved["snapshots.png"]
    panels = _panels(fig)
    assert len(panels) == 3  # t = 0, 0.1, 0.2 s
    assert [ax.get_xlabel() for ax in panels] == ["x [m]"] * 3
    assert [ax.get_ylabel() for ax in panels] == ["y [m]", "", ""]
    assert [ax.get_ylabel() for ax in fig.axes if ax not in panels] == ["pressure [Pa]"]
    one = _panels(saved["particles_000001.png"])[0]
    assert (one.get_xlabel(), one.get_ylabel()) == ("x [m]", "y [m]")


def test_snapshot_overview_of_a_3d_run_names_its_slice(tmp_path, monkeypatch):
    """In 3D the figures show the mid-width x-z slice: the axes are x and z in m, and the
    overview's title says which slice."""
    from types import SimpleNamespace

    import numpy as np

    from mpmflow.plotting.figures import plot_snapshots
    from mpmflow.plotting.mpl import pyplot

    x = np.column_stack([np.linspace(0.0, 0.3, 50), np.full(50, 0.15), np.linspace(0, 0.1, 50)])
    snaps = [
        SimpleNamespace(
            time=t,
            path=tmp_path / f"particles_{k:06d}.vtu",
            read=lambda: {"x": x, "pressure": np.linspace(0, 500, 50), "mass": np.full(50, 1e-3)},
        )
        for k, t in enumerate((0.0, 0.1))
    ]
    summary = {"grid": {"domain_used": [0.3, 0.3, 0.3], "spacing": 0.01}}
    saved = _figures(monkeypatch)
    plot_snapshots(snaps, summary, tmp_path, pyplot(), [])
    fig = saved["snapshots.png"]
    assert [ax.get_xlabel() for ax in _panels(fig)] == ["x [m]", "x [m]"]
    assert _panels(fig)[0].get_ylabel() == "z [m]"
    assert fig.get_suptitle() == "slice y = 0.15 m +- 0.005 m"


def _with_probes(run, pressure, level, positions=True):
    """The run given ``pressure`` pressure probes on a grid over the tank and ``level``
    level gauges along the floor: probes.csv (sine series) and their summary.json entries
    (what a run with so many probes writes, without running it)."""
    import json

    import numpy as np

    t = np.linspace(0.0, 0.2, 21)
    probes = {
        f"p{k}": ("Pa", [0.01 + 0.4 * (k % 50) / 50, 0.01 + 0.4 * (k // 50) / 50])
        for k in range(pressure)
    }
    probes.update({f"l{k}": ("m", [0.4 * k / max(level, 1), 0.0]) for k in range(level)})
    header = ["time [s]"] + [f"{n} [{u}]" for n, (u, _) in probes.items()]
    rows = [[f"{x:.6g}" for x in [tk, *(np.sin(tk + k) for k in range(len(probes)))]] for tk in t]
    (run / "probes.csv").write_text("\n".join(map(",".join, [header, *rows])) + "\n")
    summary = json.loads((run / "summary.json").read_text())
    summary["probes"] = {
        n: {"quantity": "pressure" if u == "Pa" else "level", "unit": u, "position": xy}
        for n, (u, xy) in probes.items()
    }
    if not positions:  # a run still going: no summary.json yet
        (run / "summary.json").unlink()
    else:
        (run / "summary.json").write_text(json.dumps(summary))
    return list(probes)


@pytest.mark.slow
def test_plot_of_2000_probes_draws_one_collection_per_panel(small_run, tmp_path, monkeypatch):
    """2,000 probes took 18 s to plot (a Line2D and a legend entry each) and the legend
    overflowed the figure. Over LEGEND_MAX probes a panel draws them as one LineCollection
    coloured by the probes' position, with a colour bar and no legend; the work is a handful
    of artists whatever the number of probes (a regression guard that does not time)."""
    from matplotlib.collections import LineCollection

    run = _copy(small_run, tmp_path)
    _with_probes(run, 1500, 500)
    saved = _figures(monkeypatch)
    assert main(["plot", str(run)]) == 0
    fig = saved["probes.png"]
    panels, bars = _panels(fig), [ax for ax in fig.axes if ax not in _panels(fig)]
    assert [ax.get_ylabel() for ax in panels] == ["pressure [Pa]", "water level [m]"]
    for ax, n in zip(panels, (1500, 500)):
        collections = [c for c in ax.collections if isinstance(c, LineCollection)]
        assert [len(c.get_segments()) for c in collections] == [n]
        assert ax.get_lines() == [] and ax.get_legend() is None
        assert len(ax.get_children()) < 30
        assert ax.get_title() == f"{n} probes, coloured by position"
    assert [b.get_ylabel() for b in bars] == ["probe's x [m]", "probe's x [m]"]
    assert panels[-1].get_xlabel() == "time [s]"


def _probes_figure(run, monkeypatch):
    """probes.png's figure alone (what `mpmflow plot` draws, without the snapshots)."""
    from mpmflow import open_run
    from mpmflow.plotting.figures import plot_probes
    from mpmflow.plotting.mpl import pyplot

    results, saved = open_run(run), _figures(monkeypatch)
    plot_probes(results.probes, results.summary, results.units, run / "probes.png", pyplot(), [])
    return saved["probes.png"]


def test_plot_of_many_probes_without_positions_says_what_the_colour_is(
    small_run, tmp_path, monkeypatch
):
    """A run still going has no summary.json, so no probe positions: the colour is the
    probe's column in probes.csv, and the colour bar says so (not a position)."""
    run = _copy(small_run, tmp_path)
    _with_probes(run, 20, 0, positions=False)
    fig = _probes_figure(run, monkeypatch)
    assert [ax.get_ylabel() for ax in fig.axes] == ["pressure [Pa]", "probe's column in probes.csv"]
    assert fig.axes[0].get_title() == "20 probes"


def test_plot_of_a_few_probes_names_each_in_the_legend(small_run, tmp_path, monkeypatch):
    """Up to LEGEND_MAX probes per panel: a line and a legend entry each, each its own
    colour."""
    from mpmflow.plotting.figures import LEGEND_MAX

    run = _copy(small_run, tmp_path)
    names = _with_probes(run, LEGEND_MAX, 2)
    pressure, level = _panels(_probes_figure(run, monkeypatch))
    labels = [t.get_text() for t in pressure.get_legend().get_texts()]
    assert labels == names[:LEGEND_MAX]
    assert len({line.get_color() for line in pressure.get_lines()}) == LEGEND_MAX
    assert [t.get_text() for t in level.get_legend().get_texts()] == names[LEGEND_MAX:]


@pytest.mark.slow
def test_3d_run_draws_the_water_surface_beside_the_slice(tmp_path, monkeypatch):
    """In 3D `mpmflow plot` draws, beside each snapshot's slice (particles_NNNNNN.png), the
    water's surface (snapshots/surface_NNNNNN.png) and an overview of the same snapshots
    (surfaces.png): 3D axes named x, y, z in m over the domain, the surface of the block
    of particles as one collection of triangles. A snapshot without water (its volume
    fraction under 1/2 everywhere) is drawn empty, not refused."""
    from types import SimpleNamespace

    import numpy as np
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    from mpmflow.plotting.figures import plot_snapshots
    from mpmflow.plotting.mpl import pyplot

    axes = [np.arange(0.0025, a, 0.005) for a in (0.1, 0.3, 0.1)]  # 8 particles per cell
    x = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    mass = np.full(len(x), 1000.0 * 0.005**3)
    frames = {0.0: mass, 0.1: mass, 0.2: 0.4 * mass}  # the last: a fraction 0.4 everywhere
    snaps = [
        SimpleNamespace(
            time=t,
            path=tmp_path / f"particles_{k:06d}.vtu",
            read=lambda m=m: {"x": x, "pressure": x[:, 2], "mass": m},
        )
        for k, (t, m) in enumerate(frames.items())
    ]
    summary = {
        "grid": {"domain_used": [0.3, 0.3, 0.3], "spacing": 0.01, "cells": [30] * 3},
        "case": {"material": {"density": 1000.0}},
    }
    saved = _figures(monkeypatch)
    written = plot_snapshots(snaps, summary, tmp_path, pyplot(), [])
    names = [f"surface_{k:06d}.png" for k in range(3)]
    assert [p.name for p in written[-4:]] == [*names, "surfaces.png"]
    for p in written:
        assert p.stat().st_size > 1000, p
    overview = saved["surfaces.png"]
    assert len(overview.axes) == 3
    for fig in (overview, *(saved[n] for n in names)):
        for ax in fig.axes:
            assert (ax.get_xlabel(), ax.get_ylabel(), ax.get_zlabel()) == (
                "x [m]",
                "y [m]",
                "z [m]",
            )
            assert ax.get_xlim() == (0.0, 0.3) and ax.get_zlim() == (0.0, 0.3)
    assert overview.get_suptitle() == "water surface (volume fraction 1/2)"
    (full,) = [c for c in saved[names[0]].axes[0].collections if isinstance(c, Poly3DCollection)]
    assert saved[names[0]].axes[0].get_title() == "t = 0.000 s"
    (empty,) = [c for c in saved[names[2]].axes[0].collections if isinstance(c, Poly3DCollection)]
    assert len(full.get_facecolor()) > 100 and len(empty.get_facecolor()) == 0


def test_3d_pictures_without_scikit_image_are_left_out_with_a_note(tmp_path, monkeypatch):
    """Without scikit-image the slices are drawn and the note says how to get the 3D
    pictures (not a traceback after the slices)."""
    import sys
    from types import SimpleNamespace

    import numpy as np

    from mpmflow.plotting.figures import plot_snapshots
    from mpmflow.plotting.mpl import pyplot

    monkeypatch.setitem(sys.modules, "skimage", None)
    x = np.random.default_rng(1).uniform(0.0, 0.1, (200, 3))
    snaps = [
        SimpleNamespace(
            time=0.0,
            path=tmp_path / "particles_000000.vtu",
            read=lambda: {"x": x, "pressure": x[:, 2], "mass": np.full(200, 1e-3)},
        )
    ]
    summary = {"grid": {"domain_used": [0.1, 0.1, 0.1], "spacing": 0.01}}
    notes = []
    written = plot_snapshots(snaps, summary, tmp_path, pyplot(), notes)
    assert [p.name for p in written] == ["particles_000000.png", "snapshots.png", "animation.gif"]
    assert notes == [
        "mpmflow plot needs scikit-image for the 3D water surface: pip install "
        "'mpmflow[plot]' (or pip install scikit-image). The 3D pictures are "
        "left out."
    ]
