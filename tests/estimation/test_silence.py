"""The silent-gyro check: a heading that stands still while the encoders turn the body."""

from __future__ import annotations

import math

import pytest

from omnibot.errors import ConfigError
from omnibot.estimation.estimator import PoseEstimator
from omnibot.estimation.registry import make_estimator
from omnibot.estimation.silence import SILENT_TURN, GyroSilence
from omnibot.robot import load_robot
from tests.estimation.test_estimator import Sample, telemetry


def test_a_still_heading_is_silent_once_the_encoders_turned_the_threshold() -> None:
    check = GyroSilence()
    step = SILENT_TURN / 10.5
    found = [check.update(0.0, step) for _ in range(12)]
    assert found == [False] * 11 + [True]  # the first sample only sets the heading to compare with
    assert check.silent and check.turned >= SILENT_TURN
    assert "10 degrees" in check.finding() or "11 degrees" in check.finding()
    assert not check.update(0.0, step)  # said once


def test_any_change_of_the_heading_starts_the_count_again() -> None:
    check = GyroSilence()
    step = SILENT_TURN / 4
    for k in range(40):  # a working gyro at 0.01 degree steps: a change every third sample
        assert not check.update(math.radians(0.01 * (k // 3)), step)
    assert not check.silent


def test_wobble_and_a_missing_group_do_not_add_up() -> None:
    check = GyroSilence()
    for k in range(1000):  # the wheels' wobble on a straight run: net rotation zero
        check.update(0.0, 0.02 * (-1) ** k)
        check.update(None, 1.0)  # a sample without the gyro group says nothing
    assert not check.silent


def test_the_estimator_turns_to_the_encoders_with_one_alert() -> None:
    """The controller sends heading 0 (no gyro) while the body spins: the fused filter alone holds
    the heading still; the check puts the encoders' rotation in its place."""
    samples, sim = telemetry("omni4", [(0.5, [0, 0, 0, 0]), (2.0, [60, 60, 60, 60])])
    silent = [Sample(s.controller_time, s.encoders, s.tracking, 0.0) for s in samples]
    assert abs(sim.pose.theta) > 1.0  # the body turned a lot
    for name in ("fused", "encoders+raw-gyro"):
        est = make_estimator(name, sim.robot)
        for s in silent:
            est.update(s)
        assert len(est.alerts) == 1 and "stood still" in est.alerts[0], name
        assert est.estimate.theta == pytest.approx(sim.pose.theta, abs=0.05), name
        assert est.silence.silent  # type: ignore[attr-defined]
    working = make_estimator("fused", sim.robot)
    for s in samples:
        working.update(s)
    assert working.alerts == [] and working.estimate.theta == pytest.approx(sim.pose.theta, abs=0.01)


def test_fused_is_the_encoders_heading_on_a_robot_without_a_gyro() -> None:
    omni4 = load_robot("omni4")
    robot = omni4.model_copy(update={"gyro": None})
    fused = make_estimator("fused", robot)
    assert isinstance(fused, PoseEstimator) and fused.heading_source == "encoders"
    with pytest.raises(ConfigError, match="has no gyro"):
        make_estimator("encoders+gyro", robot)
