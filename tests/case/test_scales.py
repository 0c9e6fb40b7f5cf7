"""Inputs whose scale makes the pressure solve meaningless are refused before the run, by
key and with the reason (issue 40): density = 1e300 and gravity = [0, -1e300] ran into
"pressure solve did not converge ... try a smaller time.dt"."""

import pytest

from mpmflow import load_case
from mpmflow.case.sections import MAX_DENSITY, MAX_GRAVITY, MAX_PRESSURE, MIN_DENSITY
from mpmflow.cli import main
from mpmflow.errors import CaseError


@pytest.mark.parametrize(
    ("setting", "said"),
    [
        ("material.density=1e300", "`material.density` = 1e+300 is not allowed"),
        ("material.density=0.5", "`material.density` = 0.5 is not allowed"),
        ("physics.gravity=[0, -1e300]", "its magnitude is 1e+300 m/s^2, above 10000 m/s^2"),
        ("physics.gravity=[1e300, 1e300]", "its magnitude is 1.414e+300 m/s^2"),  # no overflow
        ("physics.gravity=[0, -2e4]", "`physics.gravity` = [0, -20000.0] is not allowed"),
        ("domain.size=[1e9, 1e9]", "x 1e+09 m = 9.81e+12 Pa, is above 1e+12 Pa"),
    ],
)
def test_a_scale_no_flow_has_is_refused_before_the_run(
    tiny_case_file, tmp_path, capsys, setting, said
):
    code = main(["run", str(tiny_case_file), "--out", str(tmp_path / "o"), "-q", "--set", setting])
    err = capsys.readouterr().err
    assert code == 2 and said in err, err
    assert "Traceback" not in err and "did not converge" not in err
    assert not (tmp_path / "o").exists()


def test_the_ranges_hold_every_real_material_and_centrifuge(tiny_case_file):
    for density in (MIN_DENSITY, 71.0, 1000.0, 13546.0, 22590.0, MAX_DENSITY):
        assert (
            load_case(tiny_case_file, [f"material.density={density}"]).material.density == density
        )
    # 1,000 g in a centrifuge, sideways and down
    case = load_case(
        tiny_case_file, [f"physics.gravity=[{MAX_GRAVITY * 0.6}, {-MAX_GRAVITY * 0.8}]"]
    )
    assert case.physics.gravity == [MAX_GRAVITY * 0.6, -MAX_GRAVITY * 0.8]
    assert load_case(tiny_case_file, ["physics.gravity=[0, 0]"]).physics.gravity == [0.0, 0.0]


def test_the_pressure_scale_is_measured_along_gravity(tiny_case_file):
    """The height is the domain's extent along gravity: a tall domain with gravity along
    its short side passes where the same gravity down its long side is refused."""
    g = MAX_GRAVITY
    height = MAX_PRESSURE / (MAX_DENSITY * g) * 1.5  # over the limit along it
    tall = [f"domain.size=[0.2, {height}]", f"material.density={MAX_DENSITY}"]
    load_case(tiny_case_file, [*tall, f"physics.gravity=[{-g}, 0]"])
    with pytest.raises(CaseError, match="hydrostatic pressure over the domain's height"):
        load_case(tiny_case_file, [*tall, f"physics.gravity=[0, {-g}]"])
