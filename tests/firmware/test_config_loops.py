"""config_loops.py: the closed loops' keys (the acceleration feedforward)."""

from __future__ import annotations

import pytest

from omnibot.firmware import config as fwconfig
from omnibot.robot import load_robot


def test_acceleration_feedforward_pushes_each_wheel_its_way() -> None:
    """body_ff: a wheel's PWM counts per m/s^2 of the body's acceleration along x and y and per
    rad/s^2 of its angular acceleration; they drive the wheel the way the body's velocity in the same
    direction turns it (same signs as J), a heavier robot needs proportionally more of x and y and a
    larger yaw inertia more of w; wheel_ff (its own and its rotor's inertia) is positive and small."""
    for name in ("mecanum4", "omni3"):
        robot = load_robot(name)
        cfg = fwconfig.build_config(robot)
        for row, j in zip(cfg["body_ff"], cfg["J"], strict=True):
            assert len(row) == 3
            for a, w in zip(row, j, strict=True):
                assert a * w > 0 or (a == 0 and abs(w) < 1e-9)
        heavy = fwconfig.build_config(robot.model_copy(update={"mass": 2 * robot.mass}))
        spun = fwconfig.build_config(robot.model_copy(update={"yaw_inertia": 2 * robot.yaw_inertia}))
        for row, h, s in zip(cfg["body_ff"], heavy["body_ff"], spun["body_ff"], strict=True):
            assert h[0] == pytest.approx(2 * row[0]) and h[1] == pytest.approx(2 * row[1]) and h[2] == row[2]
            assert s[2] == pytest.approx(2 * row[2]) and s[:2] == row[:2]
        ff = cfg["wheel_ff"]
        assert len(ff) == robot.n_wheels and all(0 < f < 0.01 * max(map(abs, cfg["body_ff"][0])) for f in ff)
