"""The motor map on the host: the firmware's formula mirrored, offsets, balance courses, tables."""

from __future__ import annotations

import math

import pytest
from hypothesis import given
from hypothesis import strategies as st

from omnibot.calibration.motorfit import Balance, balance_courses, identity, offsets_from_deadbands
from omnibot.calibration.patterns import Geometry, apply_map, course_pattern, map_power, top_power
from omnibot.firmware.calibration import Calibration
from omnibot.robot.description import MotorMapSpec, PiecewiseLinear, RobotDescription, load_robot

MAP = MotorMapSpec(
    offset=(36.2, 44.5, 0.0, 40.0),
    gain=(
        PiecewiseLinear(x=(21.0, 105.0, 178.0), y=(0.98, 1.02, 1.0)),
        PiecewiseLinear(x=(0.0,), y=(1.0,)),
        PiecewiseLinear(x=(50.0,), y=(1.2,)),
        PiecewiseLinear(x=(10.0, 200.0), y=(0.9, 1.1)),
    ),
)


@given(st.integers(0, 3), st.floats(-255, 255, allow_nan=False))
def test_map_power_is_the_firmwares(i: int, a: float) -> None:
    fw = Calibration(
        {
            "k": 100.0,
            "kl_courses": [0],
            "kl_tables": [[[0], [1.0]]],
            "kt": [[0], [1.0]],
            "kr": [[0], [1.0]],
            "motor_offset": list(MAP.offset),
            "motor_gain": [[list(g.x), list(g.y)] for g in MAP.gain],
        }
    )
    assert map_power(MAP, i, a) == pytest.approx(fw.motor_power(i, a), abs=1e-9)


def test_patterns_through_the_map(omni4: RobotDescription) -> None:
    geo = Geometry.of(omni4)
    assert map_power(None, 0, -12.5) == -12.5 and map_power(identity(4), 2, 7.0) == 7.0
    assert course_pattern(geo, 0.0, 100, MAP) == [0, 144, 0, -round(40 + 100 * (0.9 + 0.2 * 90 / 190))]
    assert apply_map(MAP, [250.0, 0.0, 0.0, 0.0], 255) == [255, 0, 0, 0]  # clipped
    assert top_power(MAP, 255) == 195  # motor 4: (255 - 40) / 1.1
    assert top_power(None, 255) == 255


def test_offsets_scale_the_motor_dead_bands_to_rotation() -> None:
    assert offsets_from_deadbands([50, 60, 62, 50], 40, 255) == (36.0, 43.2, 44.7, 36.0)
    assert offsets_from_deadbands([50, 256, 62, 50], 40, 255) == (0.0,) * 4  # a motor never moved it
    assert offsets_from_deadbands([50, 60, 62, 50], 256, 255) == (0.0,) * 4


def test_balance_courses_and_tables() -> None:
    assert balance_courses(Geometry.of(load_robot("omni4"))) == [
        0.0,
        45.0,
        90.0,
        135.0,
        180.0,
        225.0,
        270.0,
        315.0,
    ]
    assert len(balance_courses(Geometry.of(load_robot("omni3")))) == 12
    b = Balance(powers=[50, 100], log_gains=[[0.1, -0.1], [0.0, 0.0]])
    tables = b.tables(2)
    assert tables[0] == PiecewiseLinear(x=(50.0, 100.0), y=(round(math.exp(0.1), 3), 1.0))
    assert Balance().tables(3) == identity(3).gain
