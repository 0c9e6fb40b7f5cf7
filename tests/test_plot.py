"""`mpmflow plot`: time-series plots, particle snapshots and the animation of a run."""

import shutil

import pytest
from PIL import Image

from mpmflow.cli import main

from conftest import EXAMPLES


def test_plot_makes_the_figures_and_the_animation(tmp_path, capsys):
    run = tmp_path / "run"
    assert main(["run", str(EXAMPLES / "dam_break.toml"), "--out", str(run), "-q",
                 "--set", "grid.spacing=0.0114", "--set", "time.dt=0.01",
                 "--set", "time.end=0.3", "--set", "output.snapshot_interval=0.1"]) == 0
    assert main(["plot", str(run)]) == 0
    plots = run / "plots"
    names = ["timeseries.png", "snapshots.png", "animation.gif",
             *(f"snapshots/particles_{k:06d}.png" for k in range(4))]
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
    assert main(["run", str(EXAMPLES / "dam_break.toml"), "--out", str(run), "-q",
                 "--set", "grid.spacing=0.02", "--set", "time.dt=0.01",
                 "--set", "time.end=0.2", "--set", "output.snapshot_interval=0.1"]) == 0
    return run


def _copy(run, tmp_path):
    out = tmp_path / "run"
    shutil.copytree(run, out, ignore=shutil.ignore_patterns(".mpmflow.lock", "plots"))
    return out


@pytest.mark.parametrize("content, words", [
    (b"lorem ipsum dolor sit amet\nconsectetur\n", "is not an mpmflow table"),
    (bytes(range(256)) * 8, "is not a text file (it holds binary data)"),
    (b"time,front,height\n", "holds no rows yet"),
    (b"time,front,height\n0,0.1,0.2\n0.1,zz,0.2\n", "line 3, is damaged"),
    (b"", "is not an mpmflow table"),
])
def test_plot_of_a_damaged_time_series_is_one_clear_error(small_run, tmp_path, capsys,
                                                          content, words):
    """A garbage, binary, empty or header-only timeseries.csv raised a traceback."""
    run = _copy(small_run, tmp_path)
    (run / "timeseries.csv").write_bytes(content)
    capsys.readouterr()
    assert main(["plot", str(run)]) == 2
    err = capsys.readouterr().err
    assert words in err and "Traceback" not in err and err.count("\n") == 1, err


@pytest.mark.parametrize("damage, words", [
    ("missing", "is missing: the index particles.pvd lists it"),
    ("truncated", "cannot be read"),
    ("garbage", "cannot be read"),
])
def test_plot_leaves_out_a_missing_or_damaged_snapshot_with_a_note(small_run, tmp_path,
                                                                   capsys, damage, words):
    """A missing VTU raised a traceback, a truncated one exit 1: the others are plotted
    and the note names the file."""
    run = _copy(small_run, tmp_path)
    vtu = run / "particles_000001.vtu"
    data = vtu.read_bytes()
    if damage == "missing":
        vtu.unlink()
    else:
        vtu.write_bytes(data[:len(data) // 2] if damage == "truncated" else b"\x00junk" * 99)
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
    from mpmflow import plots

    saved, save = {}, plots.save

    def record(fig, path, dpi):
        saved[path.name] = fig
        save(fig, path, dpi)

    monkeypatch.setattr(plots, "save", record)
    return saved


def _panels(fig):
    return [ax for ax in fig.axes if ax.get_label() != "<colorbar>"]


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

    from mpmflow.mpl import pyplot
    from mpmflow.plots import plot_snapshots

    x = np.column_stack([np.linspace(0.0, 0.3, 50), np.full(50, 0.15), np.linspace(0, 0.1, 50)])
    snaps = [SimpleNamespace(time=t, path=tmp_path / f"particles_{k:06d}.vtu",
                             read=lambda: {"x": x, "pressure": np.linspace(0, 500, 50)})
             for k, t in enumerate((0.0, 0.1))]
    summary = {"grid": {"domain_used": [0.3, 0.3, 0.3], "spacing": 0.01}}
    saved = _figures(monkeypatch)
    plot_snapshots(snaps, summary, tmp_path, pyplot(), [])
    fig = saved["snapshots.png"]
    assert [ax.get_xlabel() for ax in _panels(fig)] == ["x [m]", "x [m]"]
    assert _panels(fig)[0].get_ylabel() == "z [m]"
    assert fig._suptitle.get_text() == "slice y = 0.15 m +- 0.005 m"
