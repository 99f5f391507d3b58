"""The tracker on paths whose heading changes along the way, on the real stack in lockstep (firmware,
physics, the robot's own estimate; errors against the simulator's ground truth), fixed seeds."""

from __future__ import annotations

import numpy as np
import pytest

from omnibot.control.followers.base import make_follower
from omnibot.control.followers.tracker import HEADING_GAIN, ProfileTracker, heading_gain
from omnibot.control.paths import smooth_random_path, standard_path
from omnibot.navigation import FollowOptions
from omnibot.navigation.session import follower_limits, simulate_follow
from omnibot.protocol import codes
from omnibot.robot import load_robot


@pytest.mark.parametrize(
    ("preset", "heading", "speed"),
    [("omni4", "swing", 1.0), ("omni3", "tangent", 2.0)],
)
def test_tracker_holds_a_turning_body_on_a_random_path(preset: str, heading: str, speed: float) -> None:
    robot = load_robot(preset)
    path = smooth_random_path(1, length=2.0, radius_min=0.4, wavelength=1.0, heading=heading)
    assert path.theta.max() - path.theta.min() > 0.5  # the body really turns
    _, report = simulate_follow(
        robot, path, FollowOptions(follower="tracker", speed=speed, standstill=1.0), seed=4
    )
    assert report["completed"], report["failures"]
    assert report["rms_cross_track_m"] <= 0.01
    assert report["max_cross_track_m"] <= 0.03
    assert report["time_ratio"] <= 1.25
    assert report["rms_heading_error_rad"] <= 0.05


def test_tracker_steers_its_estimate_closer_than_seed002_when_the_body_swings() -> None:
    # against the truth both carry the same driven-wheel odometry (on this path its error, 1-2 cm,
    # is larger than either follower's), so the followers are compared on what they steer: the estimate
    robot = load_robot("omni4")
    path = standard_path("s_curve", size=0.6, heading="swing")
    own, reports = {}, {}
    for name in ("tracker", "seed002"):
        run, reports[name] = simulate_follow(
            robot, path, FollowOptions(follower=name, speed=0.8, standstill=1.0), seed=5
        )
        dist, _ = path.nearest(run.arrays()["estimate"][:, :2])
        own[name] = float(np.sqrt(np.mean(dist**2)))
    ours = reports["tracker"]
    assert ours["completed"]
    assert ours["rms_cross_track_m"] <= 0.01 and ours["max_cross_track_m"] <= 0.03
    assert own["tracker"] < 0.5 * own["seed002"]
    assert ours["time_ratio"] <= 1.25


@pytest.mark.parametrize(
    ("preset", "gain"), [("omni4", HEADING_GAIN), ("mecanum4", HEADING_GAIN), ("omni3", 4.0)]
)
def test_heading_gain_is_what_the_angular_acceleration_delivers(preset: str, gain: float) -> None:
    limits = follower_limits(load_robot(preset), 1.0)
    assert heading_gain(limits, 0.04) == pytest.approx(gain)
    default, given = make_follower("tracker", limits), make_follower("tracker", limits, heading=6.0)
    assert isinstance(default, ProfileTracker) and isinstance(given, ProfileTracker)
    assert default.k_heading == pytest.approx(gain)
    assert given.k_heading == 6.0


def test_tracker_keeps_omni3_on_a_swinging_lemniscate_on_carpet() -> None:
    # the heavy robot (30 kg, 10 rad/s^2) starting the swing at full acceleration on carpet: its
    # wheel 0 skids for seconds and the body falls behind in heading; a heading loop of 8/s then
    # spent the grip the translation needed (max 3.73 cm here, 3.55 cm in the benchmark), the
    # 4/s its angular acceleration delivers leaves it (2.08 cm)
    robot = load_robot("omni3")
    path = standard_path("lemniscate", size=3.0, heading="swing")
    _, report = simulate_follow(
        robot,
        path,
        FollowOptions(follower="tracker", speed=5.0, calibrate_gyro=True),
        surface="carpet",
        seed=1,
    )
    assert report["completed"], report["failures"]
    assert report["rms_cross_track_m"] <= 0.01
    assert report["max_cross_track_m"] <= 0.03
    assert report["time_ratio"] <= 1.25


def test_a_command_beyond_the_robots_reach_is_scaled_as_a_whole() -> None:
    """omni3 at top speed with the body swinging: the feedback asked more than the wheels give, the
    wheel loops saturated one by one, the turn fell behind and then overshot past the gyro's range.
    The tracker now sends the twist it asks, scaled down to the reach, course and turn share kept."""
    from omnibot.control.followers.base import Command
    from omnibot.control.followers.tracker import within_reach

    robot = load_robot("omni3")
    limits = follower_limits(robot, 5.0)
    rows = np.array(limits.wheels)
    asked = Command(1.29, 4.44, 2.66)  # seed 2's wood line-swing, 0.3 s before the body overshot
    assert np.max(np.abs(rows @ np.array(asked))) > 1.0
    sent = within_reach(limits, asked)
    assert np.max(np.abs(rows @ np.array(sent))) == pytest.approx(1.0)
    np.testing.assert_allclose(np.array(sent) / np.array(asked), sent.w / asked.w)
    assert within_reach(limits, Command(2.0, 0.5, 1.0)) == Command(2.0, 0.5, 1.0)  # within: as asked
    # on a floor, what its load leaves the motors: less than the free-running wheels
    wood = follower_limits(robot, 5.0, "wood")
    assert wood.floor is not None
    on_wood = within_reach(wood, asked)
    assert on_wood.w < sent.w and wood.floor.multiple(np.array([on_wood]))[0] == pytest.approx(1.0)


def test_the_body_acceleration_in_vel_shares_the_turning_start_among_the_wheels(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """mecanum4 on carpet, a circle with the body swinging at its top speed (no slip calibration):
    with the profile's whole acceleration fed forward (protocol version 4) each wheel pushes its
    share of the body's force and torque from the start of every change, and the robot keeps closer
    to the path at the turning starts than with version 3, whose A goes only with straight runs
    (none here), so the wheel loops learn every acceleration in their integrals. Before the closed
    loop fed a wheel that mostly turns the body ROTATE's K_r at its own speed (motion.py
    ``_turning_floor``), the version 3 run lost more at each turning start: 0.93 -> 0.71 cm RMS.

    Seeds 1 and 2 together: one seed's run is a draw (seeds 1-8, 2026-12-07: version 4's max
    cross-track 10 % lower than version 3's summed, 0.75-1.18 of it seed by seed; its RMS 4 % lower
    summed, 0.72-1.14 seed by seed, too close to the spread to assert on two)."""
    robot = load_robot("mecanum4")
    path = standard_path("circle", size=1.0, heading="swing")
    options = FollowOptions(follower="tracker", speed=0.8, standstill=1.0, floor="carpet")
    assert codes.VERSIONS[-1] == 4
    worst = []
    for versions in (codes.VERSIONS, (2, 3)):  # host and controller of version 4, then of version 3
        monkeypatch.setattr(codes, "VERSIONS", versions)
        runs = [simulate_follow(robot, path, options, surface="carpet", seed=seed)[1] for seed in (1, 2)]
        assert all(run["completed"] for run in runs)
        worst.append(sum(run["max_cross_track_m"] for run in runs))
    v4, v3 = worst
    assert v4 < 0.92 * v3
