"""Calibration tables, course folding and the power model."""

from __future__ import annotations

import math

import pytest

from omnibot.errors import ConfigError
from omnibot.firmware.calibration import Calibration, fold_course, interp
from omnibot.firmware.config import build_config
from omnibot.firmware.power import DEADBAND, SATURATED, PowerModel
from omnibot.robot.description import MotorMapSpec, PiecewiseLinear, load_robot
from tests.firmware.conftest import FORMULA_CALIBRATION


def test_interp_holds_outside_and_interpolates_inside() -> None:
    xs, ys = [50.0, 100.0, 200.0], [2.0, 1.0, 0.5]
    assert interp(xs, ys, 0) == 2.0
    assert interp(xs, ys, 75) == 1.5
    assert interp(xs, ys, 150) == 0.75
    assert interp(xs, ys, 999) == 0.5


@pytest.mark.parametrize(
    ("course", "folded"),
    [(0, 0), (30, 30), (45, 45), (60, 30), (90, 0), (135, 45), (-10, 10), (350, 10), (200, 20)],
)
def test_fold_course_omni4(course: float, folded: float) -> None:
    axes = build_config(load_robot("omni4"))["idle_axes"]
    assert axes == [0.0, 90.0]
    assert fold_course(course, axes) == pytest.approx(folded)


def test_idle_axes_of_three_wheels_and_mecanum() -> None:
    assert build_config(load_robot("omni3"))["idle_axes"] == [0.0, 60.0, 120.0]
    assert build_config(load_robot("mecanum4"))["idle_axes"] == [45.0, 135.0]
    axes = [0.0, 60.0, 120.0]
    assert max(fold_course(c, axes) for c in range(360)) == 30.0


def _cal_cfg() -> dict[str, object]:
    return {
        "k": 200.0,
        "kl_courses": [0, 45],
        "kl_tables": [[[0, 100], [2.0, 1.0]], [[0], [1.0]]],
        "kt": [[0], [1.0]],
        "kr": [[0, 100], [1.0, 3.0]],
    }


def _cal() -> Calibration:
    return Calibration(_cal_cfg())


def test_k_l_interpolates_power_and_course() -> None:
    cal = _cal()
    assert cal.k_l(0, 0) == 2.0
    assert cal.k_l(50, 0) == 1.5
    assert cal.k_l(50, 45) == 1.0
    assert cal.k_l(50, 22.5) == pytest.approx(1.25)
    assert cal.k_r(50) == 2.0


def test_set_knot_rules() -> None:
    cal = _cal()
    assert cal.set_knot(2, 0, 10, 1.5)  # rewriting knot 0 drops the rest
    assert cal.kr == [[10.0], [1.5]]
    assert not cal.set_knot(2, 2, 20, 1.0)  # no gaps
    assert not cal.set_knot(2, 1, 10, 1.0)  # increasing powers
    assert cal.set_knot(2, 1, 20, 1.0)
    assert not cal.set_knot(12, 0, 0, 1.0)  # curve 2 does not exist yet
    assert cal.set_knot(12, -1, 80, 0)  # add course 80
    assert cal.kl_courses == [0, 45, 80]
    assert not cal.set_knot(11, -1, 90, 0)  # courses must increase
    assert not cal.set_knot(0, 0, 0, 0.0)
    assert cal.set_knot(0, 0, 0, 300.0) and cal.k == 300.0


def test_power_model_saturation_and_dead_band() -> None:
    cfg = build_config(
        load_robot("omni4").model_copy(update={"calibration": FORMULA_CALIBRATION}), power_min=60
    )
    model = PowerModel(cfg, Calibration(cfg))
    out = [0] * 4
    assert model.compute(1.0, 0.0, 0.0, False, out) == 0
    assert out == [0, 220, 0, -220]
    flags = model.compute(2.0, 0.0, 0.0, False, out)
    assert flags == SATURATED and out == [0, 255, 0, -255]
    assert model.scale == pytest.approx(255 / 440)
    assert model.compute(0.2, 0.0, 0.0, False, out) == DEADBAND
    assert out == [0, 0, 0, 0]
    # rotation: K * R_c * w on every wheel
    model.compute(0.0, 0.0, math.pi, True, out)
    assert out == [round(220 * 0.096 * math.pi)] * 4


def test_wheel_speeds_match_kinematics() -> None:
    robot = load_robot("mecanum4")
    cfg = build_config(robot)
    model = PowerModel(cfg, Calibration(cfg))
    out = [0.0] * 4
    model.wheel_speeds(0.3, -0.2, 1.0, out)
    want = robot.wheel_matrix @ [0.3, -0.2, 1.0]
    assert out == pytest.approx(list(want))


def test_motor_map_offset_gain_and_ramp() -> None:
    cal = Calibration({**_cal_cfg(), "motors": 2})
    assert cal.offset == [0.0, 0.0] and cal.motor_power(1, -80.0) == -80.0  # identity by default
    assert cal.set_knot(3, 1, 0, 40.0) and cal.set_knot(21, 0, 100, 0.8) and cal.set_knot(21, 1, 200, 1.2)
    assert cal.motor_power(1, 50.0) == pytest.approx(40 + 0.8 * 50)
    assert cal.motor_power(1, -150.0) == pytest.approx(-(40 + 1.0 * 150))
    assert cal.motor_power(1, 0.25) == pytest.approx(0.25 * 40 + 0.8 * 0.25)  # the offset ramps in
    assert cal.motor_power(1, 0.0) == 0.0 and cal.motor_power(0, 7.0) == 7.0
    assert not cal.set_knot(3, 2, 0, 10.0)  # no motor 3
    assert not cal.set_knot(3, 0, 5, 10.0)  # X must be 0
    assert not cal.set_knot(22, 0, 0, 1.0)  # no gain table for motor 3
    assert not cal.set_knot(21, 0, 0, 0.0)  # gains are positive


def test_motor_map_speed_term() -> None:
    """``sign(a) (offset + gain |a|) + speed u``: the speed term follows the rim speed u (m/s), with the
    direction of a; it never turns a power against a, and a wheel meant to stand still stays still."""
    cal = Calibration({**_cal_cfg(), "motors": 2})
    assert cal.speed == [0.0, 0.0] and cal.motor_power(1, 80.0, 0.5) == 80.0
    assert cal.set_knot(7, 1, 0, 40.0) and cal.set_knot(21, 0, 0, 0.9)
    assert cal.motor_power(1, 80.0, 0.5) == pytest.approx(0.9 * 80 + 20)
    assert cal.motor_power(1, -80.0, -0.5) == pytest.approx(-(0.9 * 80 + 20))
    assert cal.set_knot(7, 1, 0, -400.0)
    assert cal.motor_power(1, 80.0, 0.5) == 0.0  # 72 - 200: not reversed
    assert cal.motor_power(1, 0.0, 0.5) == 0.0
    assert not cal.set_knot(7, 2, 0, 1.0) and not cal.set_knot(7, 0, 3, 1.0)  # no motor 2; X must be 0


def test_power_model_gives_each_motor_its_rim_speed() -> None:
    cfg = build_config(load_robot("omni4").model_copy(update={"calibration": FORMULA_CALIBRATION}))
    model = PowerModel(cfg, Calibration(cfg))
    out = [0] * 4
    model.compute(1.0, 0.0, 0.0, False, out)
    assert out == [0, 220, 0, -220]
    assert model.cal.set_knot(7, 1, 0, 30.0) and model.cal.set_knot(7, 3, 0, 30.0)
    model.compute(1.0, 0.0, 0.0, False, out)
    assert out == [0, 250, 0, -250]  # rim speeds +1 and -1 m/s, both 30 counts harder
    model.compute(0.0, 0.0, 1.0, True, out)  # rotation: rim speed 0.096 m/s on every wheel
    assert abs(out[1] - out[0] - 30 * 0.096) <= 1


def test_k_l_courses_lie_within_0_to_90() -> None:
    cal = _cal()
    assert not cal.set_knot(12, -1, 91, 0) and not cal.set_knot(10, -1, -1, 0)
    assert cal.set_knot(12, -1, 90, 0)


def test_dropping_k_l_curves() -> None:
    cal = _cal()
    assert not cal.set_knot(10, -2, 0, 0)  # curve 0 always stays
    assert not cal.set_knot(13, -2, 0, 0)  # beyond the curves
    assert cal.set_knot(12, -2, 0, 0)  # nothing after curve 1: no change
    assert cal.kl_courses == [0, 45]
    assert cal.set_knot(11, -2, 0, 0)
    assert cal.kl_courses == [0] and len(cal.kl) == 1
    assert cal.k_l(50, 45) == 1.5


def test_config_carries_the_motor_map() -> None:
    robot = load_robot("omni4")
    gain = PiecewiseLinear(x=(50.0,), y=(1.1,))
    spec = FORMULA_CALIBRATION.model_copy(
        update={"motors": MotorMapSpec(offset=(1, 2, 3, 4), gain=(gain,) * 4)}
    )
    cfg = build_config(robot.model_copy(update={"calibration": spec}))
    assert cfg["motor_offset"] == [1.0, 2.0, 3.0, 4.0] and cfg["motor_gain"][3] == [[50.0], [1.1]]
    assert build_config(robot)["motor_gain"] == [[[0.0], [1.0]]] * 4
    assert cfg["motor_speed"] == [0.0] * 4 and build_config(robot)["motor_speed"] == [0.0] * 4
    speedy = MotorMapSpec(offset=(1, 2, 3, 4), gain=(gain,) * 4, speed=(5.0, 0.0, -5.0, 1.5))
    fast = build_config(robot.model_copy(update={"calibration": spec.model_copy(update={"motors": speedy})}))
    assert fast["motor_speed"] == [5.0, 0.0, -5.0, 1.5]
    three = spec.model_copy(update={"motors": MotorMapSpec(offset=(1, 2, 3), gain=(gain,) * 3)})
    with pytest.raises(ConfigError, match="3 motors for a robot with 4"):
        build_config(robot.model_copy(update={"calibration": three}))
