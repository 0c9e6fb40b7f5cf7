"""output.centre_of_mass: the particles' centre of mass at the output times, and a restart
that continues its file as the uninterrupted run writes it."""

import shutil

import numpy as np
from conftest import EXAMPLES

from mpmflow import Simulation, load_case
from mpmflow.checkpoint import checkpoints


def test_the_centre_of_mass_file_follows_the_particles(tmp_path):
    case = load_case(
        EXAMPLES / "dam_break.toml",
        ["grid.spacing=0.01", "time.end=0.1", "output.centre_of_mass=true"],
    )
    sim = Simulation(case, tmp_path / "o")
    sim.run()
    rows = np.loadtxt(tmp_path / "o" / "centre_of_mass.csv", delimiter=",", skiprows=1)
    P = sim.particles
    assert rows.shape == (11, 3)  # t = 0 and ten outputs
    assert np.allclose(rows[-1, 1:], (P.mass[:, None] * P.x).sum(0) / P.mass.sum())
    assert abs(rows[0, 1] - 0.057) < 1e-3 and rows[-1, 1] > rows[0, 1]  # the column spreads


def test_a_restart_continues_the_file_as_the_whole_run_writes_it(tmp_path):
    more = ["grid.spacing=0.01", "time.end=0.1", "output.centre_of_mass=true"]
    more += ["checkpoint.interval=0.05"]
    case = load_case(EXAMPLES / "dam_break.toml", more)
    Simulation(case, tmp_path / "whole").run()
    shutil.copytree(tmp_path / "whole", tmp_path / "copy")
    older = checkpoints(tmp_path / "copy")[0]  # at 0.05 s: the rows after it are cut
    Simulation.resume(case, tmp_path / "copy", older).run()
    name = "centre_of_mass.csv"
    assert (tmp_path / "copy" / name).read_text() == (tmp_path / "whole" / name).read_text()
