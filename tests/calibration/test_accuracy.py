"""The reach of a calibration and the check tables' marks (pure functions, no simulator)."""

from __future__ import annotations

import math

from omnibot.calibration.accuracy import AccuracyRow, reach_speed
from omnibot.calibration.tables import move_grid
from omnibot.firmware.calibration import Calibration
from omnibot.firmware.config import build_config
from omnibot.firmware.power import SATURATED, PowerModel
from omnibot.robot import CalibrationSpec, PiecewiseLinear, RobotDescription, RollerDragSpec


def saturates(robot: RobotDescription, spec: CalibrationSpec, speed: float) -> bool:
    """Whether the firmware saturates a MOVE at ``speed`` on some course (no roller drag)."""
    cfg = build_config(robot.model_copy(update={"calibration": spec}))
    model = PowerModel(cfg, Calibration(cfg))
    out = [0] * model.n
    for course in range(0, 360, 15):
        a = math.radians(course)
        if model.compute(speed * math.cos(a), speed * math.sin(a), 0.0, False, out) & SATURATED:
            return True
    return False


def test_reach_is_where_the_firmware_starts_to_saturate(omni4: RobotDescription) -> None:
    assert omni4.calibration is not None
    assert reach_speed(omni4, omni4.calibration, 1.0) == 1.0  # the preset powers its whole range
    strong = omni4.calibration.model_copy(update={"k": 1.6 * omni4.calibration.k})
    reach = reach_speed(omni4, strong, 1.0)
    assert reach is not None and 0.3 < reach < 1.0
    assert not saturates(omni4, strong, reach) and saturates(omni4, strong, reach + 0.01)
    too_strong = omni4.calibration.model_copy(update={"k": 10 * omni4.calibration.k})
    assert reach_speed(omni4, too_strong, 1.0) is None


def test_reach_counts_the_roller_drag_at_its_worst(omni4: RobotDescription) -> None:
    assert omni4.calibration is not None
    strong = omni4.calibration.model_copy(update={"k": 1.6 * omni4.calibration.k})
    plain = reach_speed(omni4, strong, 1.0)
    drag = RollerDragSpec(cos=(-5.0,) * 4, sin=(3.0,) * 4)
    dragged = reach_speed(omni4, strong.model_copy(update={"rollers": drag}), 1.0)
    coast = drag.model_copy(update={"coast": PiecewiseLinear(x=(0.0, 1.0), y=(0.0, 2.0))})
    coasted = reach_speed(omni4, strong.model_copy(update={"rollers": coast}), 1.0)
    assert plain is not None and dragged is not None and coasted is not None
    assert coasted < dragged < plain


def test_grid_marks_moves_the_controller_could_not_power() -> None:
    def row(course: float, error: float, saturated: bool) -> AccuracyRow:
        return AccuracyRow("move", course, 0.9, 1.0, 1.0 + error, error, saturated=saturated)

    grid = move_grid([row(0.0, -0.05, True), row(180.0, -0.04, True), row(45.0, 0.01, False)])
    assert "| 0 | -5.0* / -4.0* |" in grid and "| 45 | +1.0 |" in grid
    assert grid.splitlines()[-1].startswith("\\* the controller warned")
    assert "warned" not in move_grid([row(45.0, 0.01, False)])
    assert AccuracyRow("move", 0.0, 0.3, 1.0, 1.0, 0.0).saturated is False
