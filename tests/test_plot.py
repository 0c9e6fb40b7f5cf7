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
