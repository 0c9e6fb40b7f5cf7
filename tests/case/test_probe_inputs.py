"""Probes that could not read anything, and measured series that are not series, are
refused before the run (issue 40): a pressure window narrower than the particles' spacing
(1e-9 m read 0 for the whole run), and a probes.N.data file with text, nan or inf in the
columns it reads or times out of order (they were accepted and plotted), each with the
file and the line."""

import numpy as np
import pytest
from conftest import TINY_CASE

from mpmflow import load_case
from mpmflow.case.probe_data import read_series
from mpmflow.cli import main
from mpmflow.errors import CaseError

# the input tests' small case with 2 particles per cell (a spacing of 0.01 m) and a probe
CASE = (
    TINY_CASE.replace("max = [0.1, 0.1]", "max = [0.1, 0.1]\nparticles_per_cell = 2")
    + """
[[probes]]
name = "p1"
quantity = "pressure"
position = [0.0, 0.02]
"""
)

SERIES = "time [s],P1 [Pa],note\n0.0,1.0,start\n0.1,2.0,\n0.2,3.0,end\n"


def _case(tmp_path, extra="", series=SERIES):
    (tmp_path / "measured.csv").write_text(series)
    path = tmp_path / "case.toml"
    path.write_text(CASE + extra)
    return path


@pytest.mark.parametrize("window", [1e-9, 0.005, 0.0099])
def test_a_window_narrower_than_the_particles_is_refused(tmp_path, capsys, window):
    path = _case(tmp_path, f"window = {window}\n")
    code = main(["run", str(path), "--out", str(tmp_path / "o"), "-q"])
    err = capsys.readouterr().err
    assert code == 2 and "Traceback" not in err
    assert f"probes.0.window = {window:g} m is narrower than the particles' spacing, 0.01 m" in err
    assert not (tmp_path / "o").exists()


def test_a_window_of_one_particle_spacing_or_more_and_a_level_probe_pass(tmp_path):
    assert load_case(_case(tmp_path, "window = 0.01\n")).probes[0].window == 0.01
    # a denser body sets the spacing: 0.005 m holds its particles
    case = load_case(_case(tmp_path, "window = 0.005\n"), ["bodies.0.particles_per_cell=4"])
    assert case.probes[0].window == 0.005


def test_a_measured_series_as_it_should_be_is_read(tmp_path):
    case = load_case(_case(tmp_path, 'data = {path = "measured.csv", column = "P1 [Pa]"}\n'))
    t, p = read_series(case.probes[0].data.path, "time [s]", "P1 [Pa]")
    assert t.tolist() == [0.0, 0.1, 0.2] and p.tolist() == [1.0, 2.0, 3.0]


@pytest.mark.parametrize(
    ("series", "said"),
    [
        (SERIES.replace("0.1,2.0", "0.1,two"), "line 3 of {p}, column 'P1 [Pa]', holds 'two'"),
        (SERIES.replace("0.1,2.0", "0.1,nan"), "line 3 of {p}, column 'P1 [Pa]', holds 'nan'"),
        (SERIES.replace("0.2,3.0", "inf,3.0"), "line 4 of {p}, column 'time [s]', holds 'inf'"),
        (SERIES.replace("0.1,2.0", "0.1,"), "line 3 of {p}, column 'P1 [Pa]', holds ''"),
        (SERIES.replace("0.2,3.0,end", "0.2"), "line 4 of {p}, column 'P1 [Pa]', is missing"),
        (SERIES.replace("0.2,3.0", "0.05,3.0"), "line 4 of {p} is at 'time [s]' = 0.05 s, before"),
        ("time [s],P1 [Pa]\n", "{p} holds no rows of numbers"),
    ],
)
def test_a_measured_series_with_text_nan_inf_or_times_out_of_order_is_refused(
    tmp_path, capsys, series, said
):
    path = _case(tmp_path, 'data = {path = "measured.csv", column = "P1 [Pa]"}\n', series)
    with pytest.raises(CaseError) as err:
        load_case(path)
    message = str(err.value)
    assert message.startswith(
        "Invalid case " + str(path) + ": probes.0.data.path = 'measured.csv': "
    )
    assert said.format(p=tmp_path / "measured.csv") in message, message
    code = main(["run", str(path), "--out", str(tmp_path / "o"), "-q"])
    assert code == 2 and "Traceback" not in capsys.readouterr().err


def test_other_columns_may_hold_anything(tmp_path):
    """Only the probe's two columns are read: a note column of words or blanks passes."""
    series = SERIES.replace("start", "pump on").replace(",end", ",nan")
    load_case(_case(tmp_path, 'data = {path = "measured.csv", column = "P1 [Pa]"}\n', series))


@pytest.mark.parametrize(
    "text",
    [
        "t,p\n0,1\n1,2\n",
        "t,p\n0,1\n\n1,2\n\n",
        't,p\n"0","1"\n1,2\n',
        "t,p\n# c\n0,1\n",
        "t,p\n0,nan\n",
        "t,p\n1,1\n0,2\n",
        "t,p\n",
        "t,p\n0\n",
        "t,p\n 0 , 1 \n",
        "\ufefft,p\n0,1\n",
        "t,p\n0,1,extra\n1,2\n",
        "t,p\n1_0,1\n",
    ],
)
def test_numpys_reading_of_a_series_agrees_with_the_line_by_line_one(tmp_path, text, monkeypatch):
    """A well-formed series is read by NumPy (and kept per file: SPHERIC's 12 probes share
    one); every other file goes to the line-by-line reading that names its fault. Both take
    and refuse the same files, with the same numbers."""
    from mpmflow.case import probe_data

    path = tmp_path / "series.csv"
    path.write_text(text, encoding="utf-8")

    def read():
        try:
            return probe_data.read_series(path, "t", "p")
        except ValueError as err:
            return str(err)

    fast = read()
    monkeypatch.setattr(probe_data, "_parsed", lambda path, cols: None)
    slow = read()
    if isinstance(slow, str):
        assert fast == slow
    else:
        assert all(np.array_equal(a, b) for a, b in zip(fast, slow))
