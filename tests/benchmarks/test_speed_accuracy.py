"""The speed-accuracy benchmark's cells: measured as each front end drives, judged against the goal."""

from __future__ import annotations

import math

import pytest
from benchmarks.speed_accuracy import Cell, measure, within_goal


@pytest.mark.parametrize("source", ["cmd_vel", "pad", "page"])
def test_omni3_on_wood_goes_at_the_speed_asked_from_every_front_end(source: str) -> None:
    cell = measure("omni3", "wood", "45", source)
    assert within_goal(cell), cell


@pytest.mark.parametrize(
    ("robot", "direction", "before"),
    [("mecanum4", "45", 0.34), ("omni4", "rotation", 0.36), ("omni4", "0", 0.36)],
)
def test_the_presets_gains_settle_a_ramped_twist_within_the_goal(
    robot: str, direction: str, before: float
) -> None:
    """cmd_vel on wood: with the gains before the presets' own (kp 0.5 K r, ki 10 K r) the wheel loop
    took ``before`` s to bring the body within 5 % (a feedforward off by 10-30 %, left to a slow
    integral); with kp 1.0 K r and ki 20 K r 0.24, 0.26 and 0.16 s."""
    cell = measure(robot, "wood", direction, "cmd_vel")
    assert within_goal(cell), cell
    assert cell.settle < before - 0.05


def test_mecanum4_sideways_on_carpet_open_and_closed_loop() -> None:
    """The issue's worst cell: 0.08-0.10 of the speed asked open loop, 0.94 on the wheel loop."""
    assert measure("mecanum4", "carpet", "90", "cmd_vel", wheel_loop=False).ratio < 0.12
    closed = measure("mecanum4", "carpet", "90", "cmd_vel")
    assert 0.92 < closed.ratio < 0.97 and abs(closed.drift_deg) < 1.0


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
