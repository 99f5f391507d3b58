"""The dead band search, on the simulated omni4 in lockstep and on a scripted robot."""

from __future__ import annotations

from omnibot.calibration.deadband import find_deadband, lowest_moving
from omnibot.calibration.runner import Runner
from omnibot.calibration.runs import STRAIGHT, RunInfo


def test_deadband_is_the_lowest_moving_power(runner: Runner) -> None:
    db = find_deadband(runner, 0.0, step=8)
    assert db.group == "course:0"
    assert 40 <= db.power <= 56  # omni4's gearbox and roller friction: about 45-50 counts on wood
    below = runner.power_run([0, db.power - 3, 0, -(db.power - 3)], 0.5, RunInfo(STRAIGHT, "x", 0.0), "t")
    assert below.truth is not None and (below.truth.distance or 0.0) < 0.005
    rot = find_deadband(runner, None, step=8)
    assert rot.group == "rotation" and 30 <= rot.power < db.power
    # every dead-band run is a seed-000 pattern
    assert all(r.command.startswith("POWER,500,") for r in runner.log if r.group.startswith("deadband"))


def test_a_search_near_an_earlier_result_brackets_it() -> None:
    tried: list[int] = []

    def attempt(power: int) -> bool:
        tried.append(power)
        return power >= 37

    assert lowest_moving(attempt, 8, 255) == 38
    first = len(tried)
    tried.clear()
    assert lowest_moving(attempt, 8, 255, near=38) == 38  # from 30 in steps of 4, then bisection
    assert tried[0] == 34 and len(tried) < first
    tried.clear()
    # a position where it moves far lower: the search ends at the bottom of its bracket (30 + 2)
    assert lowest_moving(lambda p: p >= 20, 8, 255, near=38) == 32
