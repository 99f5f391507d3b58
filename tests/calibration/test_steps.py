"""A surface's calibration as its named steps."""

from __future__ import annotations

from omnibot.calibration.accuracy import AccuracyPlan
from omnibot.calibration.patterns import Geometry
from omnibot.calibration.plan import Plan
from omnibot.calibration.steps import STEPS
from omnibot.calibration.tally import expected_runs
from omnibot.robot import load_robot


def test_every_phase_is_one_named_steps() -> None:
    """calibrate_surface is its STEPS: each progress phase ends with its own step, in the order the
    phases are expected, so the bar's total ends at the runs driven."""
    robot = load_robot("omni4")
    phases = list(expected_runs(Plan(), Geometry.of(robot), AccuracyPlan(), robot))
    stepped = [step.phase for step in STEPS if step.phase is not None]
    assert stepped == phases
    assert len({step.name for step in STEPS}) == len(STEPS)
