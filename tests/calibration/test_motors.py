"""The motor map on the host: the firmware's formula mirrored, offsets, balance courses, tables."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from omnibot.calibration.motorfit import (
    Balance,
    balance_courses,
    centred_ratios,
    emf_counts,
    identity,
    offsets_from_deadbands,
    speed_step,
    torque_of,
)
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

SPEEDY = MAP.model_copy(update={"speed": (21.6, -23.9, 0.0, 150.0)})


@given(st.integers(0, 3), st.floats(-255, 255, allow_nan=False), st.floats(-2, 2, allow_nan=False))
def test_map_power_is_the_firmwares(i: int, a: float, u: float) -> None:
    fw = Calibration(
        {
            "k": 100.0,
            "kl_courses": [0],
            "kl_tables": [[[0], [1.0]]],
            "kt": [[0], [1.0]],
            "kr": [[0], [1.0]],
            "motor_offset": list(MAP.offset),
            "motor_gain": [[list(g.x), list(g.y)] for g in MAP.gain],
            "motor_speed": list(SPEEDY.speed or ()),
        }
    )
    assert map_power(SPEEDY, i, a, u) == pytest.approx(fw.motor_power(i, a, u), abs=1e-9)


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


def test_the_speed_term_of_a_torque_constant() -> None:
    """A motor with s times the nominal torque constant (and back-EMF) needs ``a / s + (s - 1/s) E u``
    where the nominal one needs ``a``: its speed term is (s - 1/s) E, and ``torque_of`` inverts it."""
    emf = emf_counts(load_robot("omni4"))
    assert emf == pytest.approx((255 * 0.006 * 10 / (0.025 * (7.4 - 2.0)),) * 4)  # 113 counts per m/s
    for s in (0.8, 0.9, 1.0, 1.1, 1.25):
        assert torque_of((s - 1 / s) * emf[0], emf[0]) == pytest.approx(s)


def test_speed_step_finds_the_speed_terms_the_gains_left_over() -> None:
    """Motors +-10 % apart in torque constant, balanced by gains at each power: what is left depends on
    how far each run's load share (K u / a) is from the power's mean, and the speed step finds
    (s - 1/s) E from it; the ratios' means come back from ``centred_ratios``."""
    rng = np.random.default_rng(5)
    n, k, emf = 4, 190.0, 113.0
    s = np.array([1.1, 0.9, 0.9, 1.1])
    truth = (s - 1 / s) * emf / k
    truth -= truth.mean()  # a common share is the K_l tables'
    jac = rng.normal(size=(48, n))
    ratios = rng.uniform(0.2, 0.9, size=(48, n))
    ratios[::3, 0] = 0.0  # motor 1 does not drive in every run
    centred, mean = centred_ratios(ratios)
    assert mean[1] == pytest.approx(ratios[:, 1].mean())
    assert mean[0] == pytest.approx(ratios[ratios[:, 0] > 0, 0].mean()) and np.all(centred[::3, 0] == 0.0)
    e = -np.sum(jac * truth[None, :] * centred, axis=1)
    got = speed_step(jac, e, centred, np.ones(48))
    assert got * k == pytest.approx(truth * k, abs=1.0)  # counts per m/s
    assert speed_step(jac, np.zeros(48), centred, np.ones(48)) == pytest.approx(np.zeros(n))


def test_balance_rate_interpolates_the_runs() -> None:
    b = Balance(rates=[(0.0, 50, 0.2), (0.0, 50, 0.3), (0.0, 100, 0.5), (45.0, 100, 0.3), (45.0, 200, 0.5)])
    assert b.rate(50, 10.0) == pytest.approx(0.25)  # the median of course 0's runs at 50
    assert b.rate(25, 0.0) == pytest.approx(0.125)  # through 0 below the lowest power
    assert b.rate(75, 0.0) == pytest.approx(0.375)
    assert b.rate(150, 0.0) == pytest.approx(0.75)  # along the last segment above
    assert b.rate(150, 40.0) == pytest.approx(0.4)
    assert Balance().rate(100, 0.0) == 0.0
