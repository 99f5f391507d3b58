"""The speed-accuracy benchmark's cells: measured as each front end drives, judged against the goal."""

from __future__ import annotations

import math

import pytest
from benchmarks.speed_accuracy import Cell, fitted_slip, measure, within_goal


@pytest.mark.parametrize("source", ["cmd_vel", "pad", "page"])
def test_omni3_on_wood_goes_at_the_speed_asked_from_every_front_end(source: str) -> None:
    cell = measure("omni3", "wood", "45", source)
    assert within_goal(cell), cell


def test_mecanum4_sideways_on_carpet_open_and_closed_loop() -> None:
    """The issue's worst cell: 0.76 of the speed asked open loop (0.08-0.10 on the carpet of 4x wood's
    roller drag), 0.975 on the wheel loop (0.94 there)."""
    assert measure("mecanum4", "carpet", "90", "cmd_vel", wheel_loop=False).ratio < 0.85
    closed = measure("mecanum4", "carpet", "90", "cmd_vel")
    assert 0.95 < closed.ratio < 1.0 and abs(closed.drift_deg) < 1.0


def test_the_goal_needs_speed_direction_turn_and_settling() -> None:
    good = Cell(ratio=1.02, turn_ratio=math.nan, drift_deg=-2.0, settle=0.25)
    assert within_goal(good)
    for bad in (
        Cell(1.04, math.nan, 0.0, 0.1),
        Cell(1.0, math.nan, 3.5, 0.1),
        Cell(1.0, math.nan, 0.0, 0.35),
        Cell(1.0, 1.05, 0.0, 0.1),
        Cell(1.0, math.nan, 0.0, math.inf),
    ):
        assert not within_goal(bad), bad


@pytest.mark.parametrize(("robot", "direction"), [("mecanum4", "45"), ("omni4", "rotation")])
def test_a_held_speed_settles_within_the_goal_on_wood(robot: str, direction: str) -> None:
    """ROS 2's cmd_vel on wood: the loop's integral learns the feedforward's floor error twice as fast
    once the wheels' targets hold (speedctl.py); settled in 0.32 and 0.36 s before, outside the goal."""
    cell = measure(robot, "wood", direction, "cmd_vel")
    assert within_goal(cell), cell


def test_a_ramped_start_is_not_carried_past_the_speed_asked() -> None:
    """mecanum4 forward by ROS 2's cmd_vel (the host's 2 m/s^2 ramp at 50 Hz): the loop's integral
    learns against the target each period was driven for, not the staircase's next step (speedctl.py);
    it went 8 % over and settled in 0.34 s before, outside the goal (0.16 s now)."""
    cell = measure("mecanum4", "wood", "0", "cmd_vel")
    assert within_goal(cell), cell
    assert cell.settle <= 0.2


def test_a_ramp_on_carpet_with_the_floors_slip_asks_for_its_acceleration_s_creep() -> None:
    """mecanum4 sideways on carpet by ROS 2's cmd_vel with the floor's fitted slip: the tyres creep
    under the ramp's force too (the slip's compliance), so the runtime asks for that creep while
    the body accelerates; the body then follows the ramp instead of lagging its wheels and went
    5.3 % past the speed asked on the integral that caught it up (settled in 0.46 s; 0.24 s now)."""
    cell = measure("mecanum4", "carpet", "90", "cmd_vel", slip=fitted_slip("mecanum4", "carpet"))
    assert within_goal(cell), cell
