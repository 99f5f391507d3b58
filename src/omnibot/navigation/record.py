"""Teach mode: record a path from the robot's own odometry while it is driven or pushed by hand.

Three ways to move the robot while :class:`~omnibot.control.paths.teach.PathRecorder` samples the
estimator's poses (the robot's dead reckoning, as seed 002 records with its encoders):

* ``push`` (simulator only): the motors stay off and a simulated hand pushes the robot along a
  shape - seed 002's "manually moving the robot along a curve path". The hand sees where the robot
  really is (as a person does) and pushes it after a target walking along the shape at ``speed``:
  force = mass x (target acceleration + stiffness x position error + damping x velocity error), and
  a torque that holds the target heading. The robot's backdriven gearmotors resist; the hand does
  not care.
* ``drive``: the robot is driven by commands: VEL with the shape's time-optimal profile as a
  script (a stand-in for teleop; a :class:`~omnibot.runtime.sources.ScriptSource` on the
  navigator's runtime), open loop - what is recorded is what the robot actually did.
* ``listen``: nothing is sent but telemetry requests; someone else drives or pushes the robot
  (a real robot) for ``duration`` seconds or until interrupted.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

from omnibot.client import RobotClient
from omnibot.control import Path, PathRecorder, time_optimal_profile, to_body, wrap
from omnibot.errors import ConfigError
from omnibot.motion import Twist
from omnibot.navigation.outcome import MIN_LENGTH, MIN_POINTS
from omnibot.navigation.runner import Navigator
from omnibot.navigation.session import follower_limits
from omnibot.robot import RobotDescription
from omnibot.runtime import RuntimeRecording, ScriptSource
from omnibot.signals import Terminated

TEACH_MODES = ("push", "drive", "listen")
HAND_STIFFNESS = 60.0
"""1/s^2: the hand's position gain (per kg of robot)."""
HAND_DAMPING = 15.0
"""1/s: the hand's velocity gain."""
HAND_TURN_STIFFNESS, HAND_TURN_DAMPING = 60.0, 15.0


@dataclass
class TeachResult:
    """What a teach-in run gave: the recorded path, how it was taught, its duration (s) and length (m)."""

    path: Path | None
    """None when fewer than two poses were recorded."""
    mode: str
    duration: float
    distance: float
    truth_error: float | None
    """Distance between the recorded end and the true end (simulator only), m."""
    warnings: list[str] = field(default_factory=list)
    """What the runtime warned about while recording (e.g. a silent gyro)."""


def teach(
    client: RobotClient,
    robot: RobotDescription,
    recorder: PathRecorder,
    *,
    mode: str,
    shape: Path | None = None,
    speed: float = 0.3,
    duration: float = 30.0,
    estimator: str = "fused",
    recording: RuntimeRecording | None = None,
) -> TeachResult:
    """Record a path (see the module docstring for ``mode``); ``shape`` is what push/drive follow;
    ``recording`` (the command's ``--log``) records the navigator's runtime."""
    if mode not in TEACH_MODES:
        raise ConfigError(f"unknown teach mode '{mode}'; expected one of: {', '.join(TEACH_MODES)}")
    nav = Navigator(
        client,
        robot,
        estimator=estimator,
        wheel_loop=True if mode == "drive" else None,
        recording=recording,
    )
    if mode == "push" and nav.sim is None:
        raise ConfigError(
            "teach mode 'push' needs the simulator (sim://); on a real robot push it yourself with 'listen'"
        )
    if mode in ("push", "drive") and shape is None:
        raise ConfigError(f"teach mode '{mode}' needs a shape to follow")

    def sample(event: Any) -> None:
        e = nav.estimator.estimate
        recorder.add(e.t, e.x, e.y, e.theta)

    clock = client.clock
    try:
        nav.prepare()
        nav.runtime.telemetry_hooks.append(sample)  # after the runtime's estimator, as every sample
        start = clock.now()
        d0 = nav.estimator.distance
        if mode == "listen":
            _listen(client, duration)
        else:
            assert shape is not None
            _move(client, robot, nav, shape, speed, mode)
        elapsed = clock.now() - start
        distance = nav.estimator.distance - d0
    finally:
        if sample in nav.runtime.telemetry_hooks:
            nav.runtime.telemetry_hooks.remove(sample)
        nav.close()
    path = recorder.path() if len(recorder) >= 2 else None
    truth_error = None
    truth = nav.truth()
    if truth is not None and path is not None:
        truth_error = math.hypot(path.x[-1] - truth[0], path.y[-1] - truth[1])
    return TeachResult(path, mode, elapsed, distance, truth_error, list(nav.warnings))


def _listen(client: RobotClient, duration: float) -> None:
    """Let ``duration`` s of the link clock pass while the robot is moved by hand: Ctrl-C ends them
    early (the recording is kept), SIGTERM does not (it ends the command)."""
    try:
        client.sleep(duration)
    except KeyboardInterrupt as exc:
        if isinstance(exc, Terminated):
            raise


def check_recording(result: TeachResult) -> str | None:
    """Why a recording is not a path worth writing (None: it is)."""
    path = result.path
    points = 0 if path is None else len(path)
    length = 0.0 if path is None else path.length
    if path is None or points < MIN_POINTS or length < MIN_LENGTH:
        return (
            f"recorded {points} points, {length:.2f} m in {result.duration:.1f} s: a path needs at least "
            f"{MIN_POINTS} points and {MIN_LENGTH:g} m (did the robot move?)"
        )
    return None


def _move(
    client: RobotClient, robot: RobotDescription, nav: Navigator, shape: Path, speed: float, mode: str
) -> None:
    limits = follower_limits(robot, speed).scaled(0.5)
    profile = time_optimal_profile(shape.without_speed(), limits)
    end = profile.min_time + 1.0
    period = 0.01
    if mode == "drive":  # the profile as a script on the navigator's runtime

        def script(t: float) -> Twist | str:
            if t > end:
                return ScriptSource.END
            ref = profile.at(t)
            return to_body(ref.vx, ref.vy, ref.w, nav.state().theta, period)

        nav.drive(script, name="drive", period=period)
        client.sleep(0.5)
        return
    clock = client.clock
    t0 = clock.now()
    sim = nav.sim
    assert sim is not None and nav.frame is not None
    while (t := clock.now() - t0) <= end:
        ref = profile.at(t)
        # the hand works in the recording's frame, the shape drawn from where the robot stood
        x, y, th = nav.frame(sim.pose.x, sim.pose.y, sim.pose.theta)
        tw = sim.twist
        c, s = math.cos(th), math.sin(th)
        vx, vy = c * tw.vx - s * tw.vy, s * tw.vx + c * tw.vy
        x0, y0, th0 = shape.start
        home = nav.start_pose
        tx, ty, tth = ref.x - x0 + home.x, ref.y - y0 + home.y, ref.theta - th0 + home.theta
        m = robot.mass
        fx = m * (ref.ax + HAND_STIFFNESS * (tx - x) + HAND_DAMPING * (ref.vx - vx))
        fy = m * (ref.ay + HAND_STIFFNESS * (ty - y) + HAND_DAMPING * (ref.vy - vy))
        torque = robot.yaw_inertia * (
            HAND_TURN_STIFFNESS * wrap(tth - th) + HAND_TURN_DAMPING * (ref.w - tw.w)
        )
        cw, sw = math.cos(-nav.frame.dth), math.sin(-nav.frame.dth)
        fx, fy = cw * fx - sw * fy, sw * fx + cw * fy
        sim.push((fx, fy), torque, period, motors_off=True)
        client.sleep(period)
    client.stop()
    client.sleep(0.5)
