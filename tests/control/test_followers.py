"""Followers on an idealised robot (first-order velocity lag, no slip): each one completes the path,
and the registry picks them by name."""

from __future__ import annotations

import math

import numpy as np
import pytest

from omnibot.control.followers import Command, Follower, State, follower_names, make_follower
from omnibot.control.followers.base import to_body, wrap
from omnibot.control.followers.response import VelocityResponse
from omnibot.control.followers.tracker import ProfileTracker
from omnibot.control.paths import MotionLimits, Path, standard_path
from omnibot.errors import ConfigError

LIMITS = MotionLimits(v_max=0.5, a_max=2.0, w_max=6.0, alpha_max=20.0)


def simulate(
    name: str,
    path: Path,
    *,
    gain: float = 1.0,
    seconds: float = 30.0,
    follower: Follower | None = None,
    **options: object,
) -> tuple[list[float], float, bool]:
    """Run a follower at 100 Hz on a robot that reaches gain x the commanded body velocity with a
    30 ms lag; returns the cross-track distances, the time taken and whether it finished."""
    f = follower or make_follower(name, LIMITS, **options)
    dt, tau = 0.01, 0.03
    x, y, th = path.start
    vx = vy = w = 0.0  # world velocity of the robot
    f.start(path, 0.0)
    t, dist = 0.0, list[float]()
    while t < seconds:
        cmd = f.update(State(t, x, y, th, vx, vy, w))
        if f.done:
            return dist, t, True
        c, s = math.cos(th), math.sin(th)
        want_x, want_y = gain * (c * cmd.vx - s * cmd.vy), gain * (s * cmd.vx + c * cmd.vy)
        a = dt / tau
        vx, vy, w = vx + a * (want_x - vx), vy + a * (want_y - vy), w + a * (gain * cmd.w - w)
        x, y, th, t = x + vx * dt, y + vy * dt, th + w * dt, t + dt
        dist.append(float(path.distances(np.array([[x, y]]))[0]))
    return dist, t, False


def test_registry() -> None:
    assert {"seed002", "seed002-plain", "pure_pursuit", "tracker"} <= set(follower_names())
    with pytest.raises(ConfigError, match="unknown follower 'traker'; did you mean 'tracker'"):
        make_follower("traker", LIMITS)
    with pytest.raises(ConfigError, match="no option"):
        make_follower("tracker", LIMITS, wobble=1)
    assert make_follower("seed002-plain", LIMITS).reduced_overshoot is False  # type: ignore[attr-defined]


@pytest.mark.parametrize("name", ["tracker", "pure_pursuit", "seed002", "seed002-plain"])
def test_every_follower_completes_an_s_curve(name: str) -> None:
    path = standard_path("s_curve", size=1.0)
    dist, t, done = simulate(name, path)
    assert done, f"{name} did not finish in {t:.1f} s"
    limit = {"tracker": 0.01, "pure_pursuit": 0.03, "seed002": 0.02, "seed002-plain": 0.10}[name]
    assert max(dist) < limit


def test_tracker_is_near_the_minimum_time_and_tight() -> None:
    path = standard_path("lemniscate", size=1.0, heading="tangent")
    f = make_follower("tracker", LIMITS)
    f.start(path, 0.0)
    minimum = f.profile.min_time  # type: ignore[attr-defined]
    dist, t, done = simulate("tracker", path)
    assert done and t < 1.15 * minimum + 0.3
    assert math.sqrt(sum(d * d for d in dist) / len(dist)) < 0.003


def test_tracker_learns_a_slow_robot() -> None:
    tracker = make_follower("tracker", LIMITS)
    dist, _, done = simulate("tracker", standard_path("circle", size=1.0), gain=0.7, follower=tracker)
    assert done and max(dist) < 0.005
    assert isinstance(tracker, ProfileTracker) and tracker.response is not None
    np.testing.assert_allclose(tracker.response.G, 0.7 * np.eye(2), atol=0.05)


def test_response_model_inverts_a_gain() -> None:
    model = VelocityResponse(delay=0.0)
    for k in range(300):
        t = 0.01 * k
        ux, uy = 0.3 * math.cos(t), 0.3 * math.sin(t)
        model.sent(t, ux, uy, 0.5)
        model.observe(t, 0.8 * ux, 0.8 * uy, 0.4, 0.01)
    assert model.compensate(0.4, 0.0, 0.4) == pytest.approx((0.5, 0.0, 0.5), abs=0.02)


def test_body_frame_and_wrap() -> None:
    cmd = to_body(0.0, 1.0, 0.0, math.pi / 2)
    assert (cmd.vx, cmd.vy) == pytest.approx((1.0, 0.0))
    assert Command(0.3, 0.4, 0.0).speed == pytest.approx(0.5)
    assert wrap(3 * math.pi) == pytest.approx(-math.pi)
    with pytest.raises(ConfigError, match="two distinct points"):
        make_follower("tracker", LIMITS).start(Path.from_points([(0.0, 0.0), (0.0, 0.0)], theta=0.0), 0.0)


def test_tracker_does_not_hold_the_robot_inside_a_curve() -> None:
    # carried ahead along a straight line, the robot's prediction lands outside a circle by
    # v^2 lead^2 / 2R; compared with the reference there, the loop used to hold it inside by as much
    path = standard_path("circle", size=0.5)  # radius 0.25 m at 0.5 m/s, an 80 ms lead: 3.2 mm
    f = make_follower("tracker", LIMITS, lead=0.08)
    dist, _, done = simulate("tracker", path, follower=f)
    assert done
    steady = np.array(dist[len(dist) // 4 : 3 * len(dist) // 4])
    assert float(np.mean(steady)) < 0.0008


def body_lag_run(path: Path, follower: Follower, tau: float = 0.04) -> tuple[list[float], bool]:
    """A robot whose wheel loops lag in the body frame (its body velocity follows the command with
    ``tau``), as a turning robot's do; the cross-track distances and whether it finished."""
    dt = 0.01
    x, y, th = path.start
    bx = by = w = 0.0
    follower.start(path, 0.0)
    t, dist = 0.0, list[float]()
    while t < 30.0:
        c, s = math.cos(th), math.sin(th)
        cmd = follower.update(State(t, x, y, th, c * bx - s * by, s * bx + c * by, w))
        if follower.done:
            return dist, True
        a = dt / tau
        bx, by, w = bx + a * (cmd.vx - bx), by + a * (cmd.vy - by), w + a * (cmd.w - w)
        c, s = math.cos(th + 0.5 * w * dt), math.sin(th + 0.5 * w * dt)
        x, y, th, t = x + (c * bx - s * by) * dt, y + (s * bx + c * by) * dt, th + w * dt, t + dt
        dist.append(float(path.distances(np.array([[x, y]]))[0]))
    return dist, False


def test_tracker_turns_its_command_by_the_heading_it_will_have() -> None:
    # the body faces its course round a lemniscate at up to 1 m/s (turning at up to 5 rad/s): a
    # body-frame command turned by today's heading acts 40 ms later on a body already turned
    fast = MotionLimits(v_max=1.0, a_max=2.0, w_max=15.0, alpha_max=20.0)
    path = standard_path("lemniscate", size=1.0, heading="tangent")
    rms = {}
    for turn_lead in (0.0, 0.04):
        dist, done = body_lag_run(path, make_follower("tracker", fast, turn_lead=turn_lead))
        assert done
        rms[turn_lead] = math.sqrt(sum(d * d for d in dist) / len(dist))
    assert rms[0.04] < 0.3 * rms[0.0]
    assert rms[0.04] < 0.0002


@pytest.mark.parametrize(
    ("shape", "heading", "planned"),
    [
        ("line", "fixed", True),
        ("line", "tangent", True),
        ("circle", "fixed", False),
        ("circle", "tangent", False),
        ("line", "swing", False),
    ],
)
def test_tracker_plans_its_acceleration_only_going_straight_with_the_heading_held(
    shape: str, heading: str, planned: bool
) -> None:
    """planned_accel: the profile's speed-up (at most the planned a_max, braking at the end) on a
    straight path that holds the heading; none where the body turns or the path curves (VEL's A is
    the speed-up along the travel alone), but for the few cycles where the reference nearly stands
    (its start and end)."""
    path = standard_path(shape, size=1.0, heading=heading)
    f = make_follower("tracker", LIMITS)
    seen: list[float] = []
    dist, _, done = simulate("tracker", path, follower=_recording(f, seen))
    assert done and max(dist) < 0.01
    if planned:
        assert 0.5 * LIMITS.a_max < max(seen) <= LIMITS.a_max and min(seen) < -0.5 * LIMITS.a_max
        assert seen[-1] == 0.0  # STOP plans nothing
    else:  # where the reference stands nearly still, going nowhere yet, it is straight
        assert sum(1 for a in seen if a) <= 10 < len(seen) // 20


def _recording(f: Follower, seen: list[float]) -> Follower:
    """``f`` with each update's planned_accel appended to ``seen``."""
    update = f.update

    def recorded(state: State) -> Command:
        command = update(state)
        seen.append(f.planned_accel)
        return command

    f.update = recorded  # type: ignore[method-assign]
    return f


def test_tracker_plans_the_bodys_whole_acceleration_on_every_command() -> None:
    """planned_body_accel: the profile's acceleration in the command's body axes. Round a circle
    with the heading along the travel at its steady speed v, it is v^2 / R towards the centre (the
    body's left when it turns left), along the body's y, with no angular acceleration; speeding up
    from rest it points along the travel; STOP plans none."""
    path = standard_path("circle", size=1.0, heading="tangent")  # radius 0.5 m
    f = make_follower("tracker", LIMITS)
    seen: list[tuple[tuple[float, float, float] | None, float]] = []
    update = f.update

    def recorded(state: State) -> Command:
        command = update(state)
        seen.append((f.planned_body_accel, command.w))
        return command

    f.update = recorded  # type: ignore[method-assign]
    dist, _, done = simulate("tracker", path, follower=f)
    assert done and max(dist) < 0.01
    assert seen[-1][0] is None  # STOP
    planned = [(a, w) for a, w in seen if a is not None]
    assert len(planned) == len(seen) - 1
    first = planned[1][0]
    assert first is not None and first[0] > 0.5 * LIMITS.a_max * 0.7 and abs(first[1]) < 0.2 * first[0]
    v = LIMITS.v_max
    middle = planned[len(planned) // 3 : 2 * len(planned) // 3]
    for (ax, ay, alpha), w in middle:
        assert ay * w > 0 and ay == pytest.approx(v * v / 0.5, rel=0.05)
        assert abs(ax) < 0.05 and abs(alpha) < 0.05
