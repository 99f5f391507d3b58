"""The experiments over the protocol, on the simulated omni4 in lockstep (small plans)."""

from __future__ import annotations

import math

import pytest

from omnibot.calibration.experiments import (
    SLOW,
    power_levels,
    rotation_sweep,
    slow_moves,
    straight_sweep,
    turning_runs,
)
from omnibot.calibration.patterns import Geometry
from omnibot.calibration.plan import Plan
from omnibot.calibration.runner import Runner
from omnibot.calibration.runs import STRAIGHT
from omnibot.errors import ConfigError
from omnibot.robot import load_robot


def test_power_levels() -> None:
    levels = power_levels(48, 255, 8)
    assert levels[0] > 48 and levels[-1] == 255 and levels == sorted(set(levels))
    assert levels[1] - levels[0] < levels[-1] - levels[-2]  # denser near the dead band


def test_straight_sweep_brackets_the_reference_move(runner: Runner) -> None:
    plan = Plan(levels=3, directions=2, move_length=0.5)
    runs = straight_sweep(runner, plan, 45.0, 48)
    assert {r.course_deg for r in runs} == {45.0, 225.0}
    assert all(r.folded_deg == 45.0 and r.kind == STRAIGHT for r in runs)
    by_power: dict[int, set[float]] = {}
    for r in runs:
        assert r.power is not None
        by_power.setdefault(r.power, set()).add(r.duration)
    # 0.5 m moves are for at most 0.5 m/s (speed_range): the sweep stops past 1.2 x that
    assert sorted(by_power) == [88, 161]
    for power, durations in by_power.items():
        if power > 60:  # above the slow end: two durations, at least 25 % apart
            lo, hi = sorted(durations)
            assert hi / lo >= 1.25
            # and the runs of that level bracket (or nearly) the reference length
            amounts = [r.amount for r in runs if r.power == power and r.amount is not None]
            assert min(amounts) < 0.5 * 1.3 and max(amounts) > 0.5 * 0.7


def test_rotation_sweep_and_turns(runner: Runner) -> None:
    runs = rotation_sweep(runner, Plan(levels=2), 40)
    assert {r.sign for r in runs} == {1, -1}
    assert all(r.amount is not None and r.amount > 0 for r in runs)  # signed by the command: positive
    turns = turning_runs(runner, Plan(turn_curvatures=(3.0,), turn_courses_deg=(45.0,)), k=144.9)
    assert len(turns) == 2 and {t.sign for t in turns} == {1, -1}
    assert [t.duration for t in turns] == pytest.approx([1.0 / 0.65] * 2)  # each MOVE of K_l's length
    speed = 0.65  # the middle of omni4's 0.30..1.00 m/s
    for t in turns:
        assert t.commanded == pytest.approx(1.0 * 3.0, rel=0.01)  # the reference 1 m at 3/m: 172 degrees
        assert t.p_arg == pytest.approx(144.9 * Geometry.of(runner.robot).rotation_factor() * speed * 3.0)
        assert t.amount is not None and t.amount > 0.5 * (t.commanded or 0)


def test_plan_courses() -> None:
    geo = Geometry.of(load_robot("omni3"))
    assert Plan().calibrated_courses(geo) == [0.0, 10.0, 20.0, 30.0]
    assert Plan.quick().calibrated_courses(geo) == [0.0, 30.0]
    with pytest.raises(ConfigError, match=r"within 0\.\.30"):
        Plan(courses_deg=(0.0, 45.0)).calibrated_courses(geo)
    assert math.isclose(Plan(courses_deg=(0.0, 30.0)).calibrated_courses(geo)[-1], 30.0)


def test_slow_moves_drive_every_raw_course_of_each_calibrated_course(runner: Runner) -> None:
    plan = Plan(courses_deg=(0.0, 45.0), directions=2, slow_rounds=1)
    runs = slow_moves(runner, plan, 0.3)
    assert [(r.folded_deg, r.course_deg) for r in runs] == [
        (0.0, 0.0),
        (0.0, 180.0),
        (45.0, 45.0),
        (45.0, 225.0),
    ]
    assert all(r.group == SLOW and r.command.startswith("MOVE") and r.commanded == 1.0 for r in runs)
    assert all(r.truth is not None and 0.5 < (r.truth.distance or 0.0) < 1.5 for r in runs)
