"""`mpmflow plot`: time-series plots, particle snapshots and the animation of a run."""

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
