"""Case values keep their TOML types (issue 40): a number is never a boolean or a string
in quotes and a boolean is never a number or a word, in the case file and in --set alike;
each refusal names the key and says how to write the value."""

import pytest
from conftest import TINY_CASE

from mpmflow import load_case
from mpmflow.cli import main
from mpmflow.errors import CaseError


@pytest.mark.parametrize(
    ("setting", "shown", "hint"),
    [
        ("bodies.0.particles_per_cell=true", "`bodies.0.particles_per_cell` = true", "booleans"),
        (
            'domain.periodic=["yes", false]',
            "`domain.periodic.0` (entry 0 of domain.periodic)",
            "true or false",
        ),
        ('output.snapshots="no"', '`output.snapshots` = "no"', "true or false"),
        ("output.snapshots=no", '`output.snapshots` = "no"', "true or false"),  # a bare word
        ("output.snapshots=1", "`output.snapshots` = 1", "true or false"),
        ('grid.spacing="0.02"', '`grid.spacing` = "0.02"', "write 0.02 without quotes"),
        ('time.dt="0.001"', '`time.dt` = "0.001"', "write 0.001 without quotes"),
        ("bodies.0.particles_per_cell=4.0", "`bodies.0.particles_per_cell` = 4.0", "write 4"),
        ("material.density=false", "`material.density` = false", "booleans"),
        ("execution.threads=true", "`execution.threads` = true", "booleans"),
    ],
)
def test_a_value_of_another_type_is_refused_by_name(tiny_case_file, setting, shown, hint):
    with pytest.raises(CaseError) as err:
        load_case(tiny_case_file, [setting])
    assert shown in str(err.value) and hint in str(err.value), str(err.value)


def test_the_same_values_in_the_case_file_are_refused(tmp_path, capsys):
    path = tmp_path / "case.toml"
    path.write_text(
        TINY_CASE.replace("spacing = 0.02", 'spacing = "0.02"').replace(
            "snapshots = false", 'snapshots = "no"'
        )
    )
    code = main(["run", str(path), "--out", str(tmp_path / "o"), "-q"])
    err = capsys.readouterr().err
    assert code == 2 and "Traceback" not in err
    assert '`grid.spacing` = "0.02"' in err and '`output.snapshots` = "no"' in err
    assert not (tmp_path / "o").exists()


def test_numbers_and_words_of_the_right_type_still_pass(tiny_case_file):
    case = load_case(
        tiny_case_file,
        ["time.dt=1e-3", "grid.spacing=0.02", "output.snapshots=true", "execution.threads=1"],
    )
    assert case.time.dt == 1e-3 and case.output.snapshots is True
    assert load_case(tiny_case_file, ["time.dt=auto", "time.end=0.1"]).time.dt == "auto"
    # an integer stands for a float (TOML writes 1 for 1.0)
    assert load_case(tiny_case_file, ["material.density=1000"]).material.density == 1000.0


def test_python_numbers_lists_and_numpy_values_are_taken_as_toml_would_hold_them(tiny_case_file):
    np = pytest.importorskip("numpy")
    case = load_case(
        tiny_case_file,
        {
            "grid.spacing": np.float32(0.02),
            "bodies.0.max": (0.1, 0.1),
            "bodies.0.min": np.zeros(2),
            "bodies.0.particles_per_cell": np.int64(3),
        },
    )
    assert case.bodies[0].particles_per_cell == 3 and case.bodies[0].max == [0.1, 0.1]
    with pytest.raises(CaseError, match="booleans, not numbers"):
        load_case(tiny_case_file, {"bodies.0.particles_per_cell": np.bool_(True)})


def test_a_refused_string_is_shown_escaped_on_one_line(tiny_case_file):
    """The value is shown as TOML writes it: a line break inside a string (here U+0085,
    which splitlines takes for one) is escaped, so the message stays one line."""
    with pytest.raises(CaseError) as err:
        load_case(tiny_case_file, ['grid.spacing="0.02\\u0085"'])
    message = str(err.value)
    assert '`grid.spacing` = "0.02\\u0085" is not allowed' in message
    assert len(message.splitlines()) == 1
