"""Every follower's command is bounded: within the limits as given, a correction of at most
``correction_speed`` on top of the path's own speed, and no chase once the robot is farther than
``off_path`` from the path (it stops and says how far off)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from omnibot.control.followers import STOP, Command, Follower, State, make_follower
from omnibot.control.followers.base import OFF_PATH, correction_speed, within_limits
from omnibot.control.paths import MotionLimits, Path
from omnibot.errors import ConfigError

FOLLOWERS = ("tracker", "pure_pursuit", "seed002", "seed002-plain")
FAST = MotionLimits(v_max=3.0, a_max=2.0, w_max=6.0, alpha_max=20.0)
"""A robot that could go 3 m/s, on paths planned at 0.3 m/s: a chase would show."""
PATH_SPEED = 0.3


def slow_line(length: float = 3.0) -> Path:
    """A straight line along x with its own speed, ``PATH_SPEED`` m/s."""
    n = int(length / 0.05) + 1
    return Path(np.linspace(0.0, length, n), np.zeros(n), np.zeros(n), v=np.full(n, PATH_SPEED))


def drive(
    follower: Follower, path: Path, *, shove: float, at: float = 2.0, seconds: float = 20.0
) -> tuple[list[float], bool]:
    """Follow ``path`` at 100 Hz on a robot reaching the commanded body velocity with a 30 ms lag;
    at ``at`` s the robot is moved ``shove`` m to the left of where it is (a push, a localiser's
    correction). The commanded translation speeds after it, and whether the follower finished."""
    dt, tau = 0.01, 0.03
    x, y, th = path.start
    vx = vy = w = 0.0
    follower.start(path, 0.0)
    t, speeds, shoved = 0.0, list[float](), False
    while t < seconds:
        if not shoved and t >= at:
            y, shoved = y + shove, True
        cmd = follower.update(State(t, x, y, th, vx, vy, w))
        if follower.done or follower.failure:
            return speeds, follower.done
        if shoved:
            speeds.append(math.hypot(cmd.vx, cmd.vy))
        c, s = math.cos(th), math.sin(th)
        a = dt / tau
        vx += a * (c * cmd.vx - s * cmd.vy - vx)
        vy += a * (s * cmd.vx + c * cmd.vy - vy)
        w += a * (cmd.w - w)
        x, y, th, t = x + vx * dt, y + vy * dt, th + w * dt, t + dt
    return speeds, False


@pytest.mark.parametrize("name", FOLLOWERS)
def test_a_robot_pushed_off_its_path_comes_back_at_the_paths_speed_plus_the_bounded_correction(
    name: str,
) -> None:
    follower = make_follower(name, FAST)
    speeds, done = drive(follower, slow_line(), shove=0.3)
    assert done and not follower.failure
    cap = PATH_SPEED + correction_speed(FAST)  # 0.3 + 0.4 s x 2 m/s^2 = 1.1 m/s
    assert max(speeds) <= cap + 1e-9, f"{name} asked {max(speeds):.2f} m/s, the cap is {cap:.2f}"
    if name == "tracker":  # its feedback adds to the path's speed: the bound binds
        assert max(speeds) > PATH_SPEED + 0.1


@pytest.mark.parametrize("name", FOLLOWERS)
def test_a_robot_farther_than_off_path_is_not_chased(name: str) -> None:
    follower = make_follower(name, FAST)
    path = slow_line()
    speeds, done = drive(follower, path, shove=0.8)
    assert not done and not speeds  # no command after the shove but STOP
    assert follower.strayed == pytest.approx(0.8, abs=0.01)
    assert follower.failure.startswith("off the path: 80.") and "(more than 50 cm)" in follower.failure
    # once given up, for good: back on the path it still asks STOP
    back = State(3.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    assert follower.update(back) == STOP and follower.planned_body_accel is None
    follower.start(path, 4.0)  # a new start clears it
    assert not follower.failure and follower.strayed is None


def test_off_path_is_an_option() -> None:
    follower = make_follower("tracker", FAST, off_path=1.0)
    assert follower.off_path == 1.0 and OFF_PATH == 0.5
    _, done = drive(follower, slow_line(), shove=0.8)
    assert done and not follower.failure  # within its own distance: steered back
    with pytest.raises(ConfigError, match="off_path must be a positive distance"):
        make_follower("pure_pursuit", FAST, off_path=0.0)


class Reckless(Follower):
    """A law that asks more than the limits allow."""

    def command(self, state: State) -> Command:
        return Command(4.0, 3.0, -20.0)


def test_every_laws_command_is_held_within_the_limits_as_given() -> None:
    follower = Reckless(FAST)
    follower.start(slow_line(), 0.0)
    cmd = follower.update(State(0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0))
    assert math.hypot(cmd.vx, cmd.vy) == pytest.approx(FAST.v_max)
    assert cmd.vx / cmd.vy == pytest.approx(4.0 / 3.0)  # the direction kept
    assert cmd.w == -FAST.w_max
    inside = Command(0.1, 0.2, 0.3)
    assert within_limits(FAST, inside) is inside
