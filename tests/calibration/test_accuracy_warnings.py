"""The check's rows and tables with the controller's warnings 11 and 17, and the reach they bound."""

from __future__ import annotations

import math

from omnibot.calibration.accuracy import AccuracyPlan, AccuracyRow, checked_reach
from omnibot.calibration.check import run_accuracy
from omnibot.calibration.runner import Runner
from omnibot.calibration.tables import move_grid
from omnibot.calibration.tap import TelemetryTap
from omnibot.calibration.truth import TruthContext, make_truth
from omnibot.robot import load_robot
from tests.calibration.conftest import sim_client


def row(
    course: float, speed: float, error: float, saturated: bool = False, short: bool = False
) -> AccuracyRow:
    return AccuracyRow("move", course, speed, 1.0, 1.0 + error, error, saturated=saturated, short=short)


def test_grid_marks_moves_short_on_the_encoders() -> None:
    rows = [row(15.0, 0.9, -0.153, short=True), row(195.0, 0.9, 0.013), row(30.0, 0.9, -0.13, True, True)]
    grid = move_grid(rows)
    assert "| 15 | -15.3! / +1.3 |" in grid and "| 30 | -13.0*! |" in grid
    notes = grid.split("\n\n")[1:]
    assert notes[0].startswith("\\* the controller warned: speed reduced")
    assert notes[1] == "! the controller warned: the MOVE fell short of its distance on the wheel encoders"
    assert "fell short" not in move_grid([row(15.0, 0.9, 0.0)])


def test_reach_lowered_below_the_slowest_warned_move() -> None:
    rows = [row(c, v, 0.0) for v in (0.3, 0.6, 0.9) for c in (0.0, 15.0)]
    assert checked_reach(0.81, rows) == 0.81  # nothing warned
    assert checked_reach(0.81, [*rows, row(15.0, 0.9, -0.15, short=True)]) == 0.81  # beyond it anyway
    assert checked_reach(0.81, [*rows, row(15.0, 0.6, -0.15, short=True)]) == 0.3
    assert checked_reach(0.81, [*rows, row(15.0, 0.6, -0.1, saturated=True)]) == 0.3
    assert checked_reach(0.81, [*rows, row(15.0, 0.3, -0.15, short=True)]) is None
    assert checked_reach(None, rows) is None
    rotate = AccuracyRow("rotate", 0.0, 90.0, 90.0, 80.0, -0.1, saturated=True)
    assert checked_reach(0.81, [*rows, rotate]) == 0.81  # a ROTATE's rate is no MOVE speed


def test_check_rows_carry_warning_17() -> None:
    """A discharged battery (6.5 V open-circuit) makes the nominal omni4's MOVEs fall 30 % short: the
    check's rows say the controller warned 17 (and not 11: no PWM saturates)."""
    robot = load_robot("omni4")
    with sim_client(robot, "wood", seed=1) as client:
        client.link.device.sim.physics.battery_open_voltage = [6.5]  # type: ignore[attr-defined]
        tap = TelemetryTap(client, robot)
        tap.start()
        runner = Runner(client, robot, make_truth("sim", TruthContext(client, robot, tap, input)), tap)
        try:
            rows = run_accuracy(
                runner, AccuracyPlan(courses_deg=(0.0,), speeds=(0.6,), back=False, rotations=())
            )
        finally:
            runner.close()
            tap.stop()
    (r,) = rows
    assert r.short and not r.saturated and r.error is not None and r.error < -0.2
    assert math.isfinite(r.error)
