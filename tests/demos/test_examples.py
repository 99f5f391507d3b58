"""Seed 000's examples on their own: the odometry the demo keeps, the spin line's words."""

from __future__ import annotations

import re

import pytest

from omnibot.demos import examples


def number(text: str, pattern: str) -> float:
    return float(re.search(pattern, text).group(1))  # type: ignore[union-attr]


def test_the_odometry_trail_starts_at_the_start_pose() -> None:
    from omnibot.client import Telemetry
    from omnibot.motion import Pose2D
    from omnibot.robot import load_robot

    recorder = examples.Recorder(load_robot("omni4"))
    for k in range(5):  # standing at the odometry's origin before the start is known
        recorder(Telemetry(time=0.02 * k, controller_time=0.02 * k, encoders=(0, 0, 0, 0), heading=0.0))
    assert recorder.odo_trail[0] == (0.0, 0.0)
    recorder.start_at(Pose2D(1.0, 1.0, 0.0))
    recorder(Telemetry(time=0.2, controller_time=0.2, encoders=(0, 100, 0, -100), heading=0.0))
    trail = recorder.odo_trail
    assert trail[0] == (1.0, 1.0) and (0.0, 0.0) not in trail
    assert trail[-1][0] > 1.0 and abs(trail[-1][1] - 1.0) < 1e-9  # then it moves on from there


def test_the_spin_line_commands_degrees_beside_the_achieved_degrees() -> None:
    """The commanded body turn is the rate times the run's time, in degrees; the rate only in brackets."""
    line = examples.spin_commanded(examples.COMPENSATING_CURVATURE)
    turn = number(line, r"body turns ([+-][\d.]+) deg \(")
    rate = number(line, r"\((-?[\d.]+) deg/s for")
    assert rate == pytest.approx(-200, abs=1)  # 0.6 m/s x -5.8/m = -3.49 rad/s
    assert turn == pytest.approx(rate * examples.SPIN_TIME, abs=1)  # -300 deg, not -200
    assert number(line, r"path bend ([+-][\d.]+) deg") == pytest.approx(0, abs=1)  # compensated: straight
    seed = examples.spin_commanded(examples.SEED_CURVATURE)
    assert number(seed, r"body turns ([+-][\d.]+) deg \(") == pytest.approx(-206, abs=1)
    assert number(seed, r"path bend ([+-][\d.]+) deg") == pytest.approx(+94, abs=1)
