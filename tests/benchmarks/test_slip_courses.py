"""The slip-courses benchmark: a run's errors split along and across its course, on the simulator."""

from __future__ import annotations

import pytest

from benchmarks import slip_courses
from omnibot.estimation import SlipParameters
from omnibot.robot import load_robot


def test_a_strafe_over_reads_along_its_course_and_the_fitted_roll_takes_it_out() -> None:
    robot = load_robot("mecanum4")
    params = SlipParameters(roll=0.0014)  # about what `omnibot calibrate` fits on wood
    runs = slip_courses.course_runs(robot, "wood", [90.0, 0.0], 0.4, 0.4, seed=3)
    strafe, ahead = (slip_courses.course_error(robot, deg, leg, params) for deg, leg in runs)
    assert strafe.distance == pytest.approx(0.4, abs=0.02)
    assert strafe.raw[0] > 0.3  # % of the distance: the rollers' creep over-reads a strafe
    assert abs(strafe.corrected[0]) < 0.25 * strafe.raw[0]
    x, y = strafe.correction_xy  # sideways only (x: the run's few mrad of yaw)
    assert y > 0.3 and abs(x) < 0.01 * y
    # straight ahead no roller rolls: only a few mm/s sideways at the start leave a correction
    assert abs(ahead.correction_xy[0]) < 1e-3 and abs(ahead.correction_xy[1]) < 0.1 * y
    assert "| 90.0 |" in slip_courses._row(strafe)
