"""The navigation loop on the lockstep simulator: a short follow run, truth in the path's frame."""

from __future__ import annotations

import math

import numpy as np
import pytest
from benchmarks.off_path import follow_line

from omnibot.client import RobotClient
from omnibot.control import Path, correction_speed, make_follower, standard_path
from omnibot.control.paths.standard import SWING
from omnibot.errors import ConfigError
from omnibot.estimation import SlipParameters
from omnibot.motion import Pose2D, Twist
from omnibot.navigation.metrics import ODOMETRY, TRUTH, follow_report, tracking_report
from omnibot.navigation.outcome import Tolerances
from omnibot.navigation.runner import NavigationError, Navigator
from omnibot.navigation.session import (
    PLAN_FLOOR_USE,
    FollowOptions,
    follow_path,
    follower_limits,
    simulate_follow,
    simulated_client,
)
from omnibot.navigation.trace import FrameMap
from omnibot.protocol import codes
from omnibot.robot import load_robot
from omnibot.runtime import Cycle, EStop, ScriptSource


def test_tracker_follows_a_circle_against_ground_truth() -> None:
    robot = load_robot("omni4")
    path = standard_path("circle", size=0.6)
    run, report = simulate_follow(robot, path, FollowOptions(follower="tracker", speed=0.4), seed=2)
    assert report["source"] == TRUTH and report["completed"]
    for key in ("rms_cross_track_m", "max_cross_track_m", "duration_s", "min_time_s", "final_error_m"):
        assert math.isfinite(report[key])
    assert report["rms_cross_track_m"] < 0.012 and report["max_cross_track_m"] < 0.03
    assert 1.0 <= report["time_ratio"] < 1.3
    assert report["final_error_m"] < 0.03
    ticks = np.diff(run.t[:-1])
    assert np.allclose(ticks, 0.01, atol=1e-3)  # the loop runs at 100 Hz on the link clock
    assert len(run.truth) == len(run.estimate) == len(run.command)


def test_truth_is_mapped_into_the_path_frame() -> None:
    robot = load_robot("omni4")
    path = standard_path("line", size=0.3)
    shifted = Path(path.x + 2.0, path.y - 1.0, path.theta + 0.5)  # starts at (2, -1), heading 0.5
    with RobotClient.open("sim://omni4?seed=1", robot) as client:  # the simulator starts at the origin
        nav = Navigator(client, robot, start=Pose2D(*shifted.start))
        nav.prepare(0.5)
        follower = make_follower("pure_pursuit", follower_limits(robot, 0.4))
        run = nav.follow(shifted, follower)
        nav.close()
    assert run.completed
    assert run.truth[0] == pytest.approx((2.0, -1.0, 0.5), abs=1e-3)
    report = tracking_report(run, follower_limits(robot, 0.4))
    assert report["max_cross_track_m"] < 0.03 and report["final_error_m"] < 0.03
    fm = FrameMap(Pose2D(1.0, 1.0, math.pi / 2), Pose2D(0.0, 0.0, 0.0))
    assert fm(1.0, 2.0, math.pi / 2) == pytest.approx((1.0, 0.0, 0.0))


def test_report_without_truth_says_so() -> None:
    robot = load_robot("omni4")
    run, _ = simulate_follow(
        robot, standard_path("line", size=0.2), FollowOptions(follower="seed002", speed=0.3)
    )
    run.truth.clear()
    run.final_truth = None
    report = tracking_report(run, follower_limits(robot, 0.3))
    assert report["source"] == ODOMETRY and "estimate_error_m" not in report
    assert report["max_cross_track_m"] < 0.02


@pytest.mark.parametrize("name", ["omni4", "mecanum4"])
@pytest.mark.parametrize("surface", ["wood", "carpet"])
def test_gyro_calibration_spin_learns_the_scale(name: str, surface: str) -> None:
    # on carpet mecanum rollers make the body turn 2 % beyond the encoders at 1 rad/s: a spin at one
    # rate read that creep as a gyro scale error of +1.2 % (true -0.9 %); two rates tell them apart
    robot = load_robot(name)
    with simulated_client(robot, surface=surface, seed=1) as client:
        nav = Navigator(client, robot)
        drivers = Drivers()
        nav.runtime.add_sink(drivers)
        nav.prepare(0.5)
        bias, scale = nav.calibrate_gyro()
        sim = nav.sim
        heading = nav.estimator.estimate.theta
        nav.close()
    # the spins are a script on the runtime: it sent every VEL, nothing else drove
    assert drivers.sources == {"gyro-spin"} and nav.runtime.sent.vel > 500
    assert nav.runtime.sent.errors == 0
    assert sim is not None and sim.gyro is not None
    assert bias == pytest.approx(
        sim.gyro.bias, abs=1e-4
    )  # the standstills': 2e-5 (fitted with the scale: 1.3e-4)
    assert scale == pytest.approx(sim.gyro.scale_error, abs=5e-4)  # what the heading filter is told
    assert abs(sim.pose.theta) < 0.2  # one turn each way at each rate: back where it started
    assert heading == pytest.approx(
        sim.pose.theta, abs=1e-3
    )  # the estimate turned with the body (0.03 degree)


def test_the_gyro_spin_stays_within_a_small_gyros_range() -> None:
    """A gyro of 2 rad/s range: the spin at 2.5 rad/s would clip it (the heading then 36 degrees off);
    the spin is capped at 95 % of the range (a planned turn rate at 90 %)."""
    omni4 = load_robot("omni4")
    assert omni4.gyro is not None
    robot = omni4.model_copy(update={"gyro": omni4.gyro.model_copy(update={"range": 2.0})})
    with simulated_client(robot, seed=1) as client:
        nav = Navigator(client, robot)
        nav.prepare(0.5)
        nav.calibrate_gyro()
        truth = nav.truth()
        heading = nav.estimator.estimate.theta
        nav.close()
    assert truth is not None and heading == pytest.approx(truth[2], abs=2e-3)


def test_the_gyro_spin_leaves_the_heading_within_the_gyro_noise() -> None:
    # omni4 on carpet with the floor's slip calibration (as benchmarks/tracking.py's floor_slip finds
    # it): the encoders miss about 1 mrad of each spin. With the bias fitted together with the scale
    # from the spins' gyro-minus-encoder differences and the heading set from the encoders, the spin
    # left the heading 0.18 degree off (random paths 1.31 cm RMS); the bias from the standstills and
    # the rotation from the gyro leave it 0.06 (0.02-0.06 on seeds 1-4), the gyro's noise over the
    # spins' 24 s with the bias pinned by 3 s standstills
    robot = load_robot("omni4")
    slip = SlipParameters(roll=0.0162, compliance=0.0266, combined=0.0333)
    with simulated_client(robot, surface="carpet", seed=1) as client:
        nav = Navigator(client, robot, slip=slip)
        nav.prepare()
        nav.calibrate_gyro()
        truth = nav.truth()
        heading = nav.estimator.estimate.theta
        nav.close()
    assert truth is not None
    assert abs(heading - truth[2]) < math.radians(0.1)


class Drivers:
    """A runtime sink: which sources sent a twist."""

    def __init__(self) -> None:
        self.sources: set[str] = set()

    def __call__(self, cycle: Cycle) -> None:
        if cycle.sent is not None:
            self.sources.add(cycle.decision.source)


def test_a_manoeuvre_is_a_script_on_the_runtime_and_an_emergency_stop_ends_it() -> None:
    robot = load_robot("omni4")
    with RobotClient.open("sim://omni4?seed=1", robot) as client:
        nav = Navigator(client, robot)
        nav.prepare(0.2)
        sent: list[Twist] = []

        def keep(cycle: Cycle) -> None:
            if cycle.sent is not None:
                sent.append(cycle.sent)

        nav.runtime.add_sink(keep)
        nav.drive(lambda t: Twist(0.2, 0.0, 0.0) if t < 0.5 else ScriptSource.END, name="nudge")
        assert len(sent) == 50 and set(sent) == {Twist(0.2, 0.0, 0.0)}  # 0.5 s at 100 Hz
        assert "nudge" not in nav.runtime.sources  # it leaves the runtime when it ends
        stop = EStop()
        nav.runtime.add_lock(stop.lock)
        stop.press("test")
        with pytest.raises(NavigationError, match=r"stopped: manoeuvre held by emergency stop \(test\)"):
            nav.drive(lambda t: Twist(0.2, 0.0, 0.0))
        nav.close()
        moved = nav.truth()
    assert len(sent) == 50 and moved is not None and 0.05 < moved[0] < 0.15


def test_follower_limits_plan_within_a_floors_reach() -> None:
    from omnibot.control.reach import floor_speed_table

    robot = load_robot("omni4")
    assert follower_limits(robot, 1.0).floor is None  # default: the motors' free speed only
    carpet = follower_limits(robot, 1.0, "carpet")
    assert carpet.floor is not None and carpet.floor_use == PLAN_FLOOR_USE < 1
    assert carpet.floor.courses == floor_speed_table(robot, "carpet")
    assert FollowOptions().floor is None


def test_omni3_keeps_its_heading_when_its_spin_clips_the_gyro(monkeypatch: pytest.MonkeyPatch) -> None:
    """omni3 at top speed on wood with the body swinging (the tracking benchmark's top-suite
    line-swing, seed 2): accelerating, wheel 0 skids and the body spins past the gyro's 4.36 rad/s
    while the wheels read about 2 rad/s. Bridging the clipped gyro with those wheels lost 7-9
    degrees and left the path by 1.5 m; the clipped reading itself is within 0.03 rad/s. Planned
    with the robot's own accelerations (no floor) and its commands sent as asked (``reach`` off),
    as when it was found: within the floor's grip and the robot's reach the body no longer
    out-spins the gyro on this run. Whether it out-spins a 4.36 rad/s gyro rides on the overshoot
    (seed 2 did, 4.39 rad/s, until the gyro spin left the heading right; 3.76 since): here the gyro
    clips at 2.6 rad/s, above the calibration spin's 2.5, and the body out-spins it (2.65; it was
    2.74 against a 2.7 rad/s gyro until the wheel loop's integral learned a held target's floor
    error twice as fast, issue 24). With the
    body's acceleration fed forward (protocol version 4) the body no longer overshoots the plan's
    turn rate (2.45 rad/s at most) and never out-spins this gyro, so the run is the one of protocol
    version 3, with the heading of the reference's instant, and the cross-track loop at 45/s, as
    when it was found (at the tracker's 30/s since 2026-12-07 the body peaks at 2.41 rad/s, under
    the calibration spin's 2.5: no gyro range both spins keep within and this run exceeds)."""
    monkeypatch.setattr(codes, "VERSIONS", (2, 3))
    omni3 = load_robot("omni3")
    assert omni3.gyro is not None
    robot = omni3.model_copy(update={"gyro": omni3.gyro.model_copy(update={"range": 2.6})})
    length = 28.6
    along = np.linspace(0.0, length, int(length / 0.01) + 1)
    path = Path(along, np.zeros(along.size), SWING * np.sin(math.pi * along / (length / 4)))
    options = FollowOptions(
        follower="tracker",
        speed=5.0,
        calibrate_gyro=True,
        follower_options={"reach": False, "progress_heading": False, "cross": 45.0},
    )
    run, report = simulate_follow(robot, path, options, surface="wood", seed=2)
    arrays = run.arrays()
    rate = np.diff(np.unwrap(arrays["truth"][:, 2])) / np.diff(arrays["t"])
    assert robot.gyro is not None and np.max(np.abs(rate)) > robot.gyro.range  # the body out-spins the gyro
    error = np.angle(np.exp(1j * (arrays["estimate"][:, 2] - arrays["truth"][:, 2])))
    assert np.max(np.abs(error)) < math.radians(3.0)
    # The heading holds; the path does not always: this 5 m/s run at the gyro's limit is chaotic
    # (measured 2026-12-06, the client's setup now two exchanges longer: seeds 1, 4 and 5 complete,
    # seed 2 ends 17 cm off the path, seed 3 45 cm; issue 30's 5 m/s run). Held here: no worse.
    assert report["max_cross_track_m"] < 0.2


def test_a_controller_without_a_gyro_is_followed_on_the_encoders_with_a_warning() -> None:
    """The host's description has a gyro, the controller has none (as the UNO firmware): its heading
    is 0 in every TEL. Taken at its word the body turned nowhere and the tracker spun the robot
    round; the estimator finds the gyro silent and the run goes on with the encoders' heading."""
    robot = load_robot("mecanum4")
    bare = robot.model_copy(update={"gyro": None})  # what the controller's firmware is built from
    path = standard_path("circle", size=0.5, heading="tangent")
    with simulated_client(bare, seed=1, start=Pose2D(*path.start)) as client:
        run, report, nav = follow_path(client, robot, path, FollowOptions(speed=0.3))
        assert nav.truth() is not None
        with pytest.raises(NavigationError, match=r"stood still .* run without --calibrate-gyro"):
            nav.prepare(0.2)
            nav.calibrate_gyro()
        nav.close()
    assert report["completed"] and report["final_error_m"] < 0.03, report
    assert len(report["warnings"]) == 1 and "no working gyro" in report["warnings"][0]
    assert run.warnings == report["warnings"]


def test_a_robot_described_without_a_gyro_cannot_calibrate_one() -> None:
    bare = load_robot("omni4").model_copy(update={"gyro": None})
    with simulated_client(bare, seed=1) as client:
        nav = Navigator(client, bare)
        nav.prepare(0.2)
        with pytest.raises(ConfigError, match="omni4 has no gyro to calibrate"):
            nav.calibrate_gyro()
        nav.close()


def test_a_robot_shoved_far_off_its_path_is_not_chased_and_the_follow_is_not_completed() -> None:
    # omni3 (30 kg, 5 m/s) on a 3 m line; 2 s in, a hand shoves it sideways (15 N/kg for 0.3 s)
    run, follower = follow_line("omni3", "tracker", "shove")
    assert not run.completed
    assert run.failure.startswith("off the path: 5") and "(more than 50 cm), not chased" in run.failure
    report = follow_report(run, load_robot("omni3"), Tolerances())
    assert not report["completed"] and report["failures"][0] == run.failure
    # until it gave up it asked at most the path's planned speed plus the bounded correction
    asked = np.hypot(*run.arrays()["command"][:, :2].T)
    planned = follower.profile.speed.max()  # type: ignore[attr-defined]
    assert asked.max() <= planned + correction_speed(follower.limits) + 1e-9


def test_a_follow_started_beside_its_path_comes_back_within_the_limits() -> None:
    # omni4's estimate starts 30 cm beside the line (a localiser's correction, a run started away)
    run, follower = follow_line("omni4", "tracker", "offset")
    assert run.completed, run.failure
    asked = np.hypot(*run.arrays()["command"][:, :2].T)
    # the response model did not learn the recovery as a slow floor (it did: 1.27-1.30 m/s asked);
    # what it learns of the floor itself is 1-2 % (1.01 asked on this line without the correction)
    assert asked.max() <= 1.05 * follower.limits.v_max
