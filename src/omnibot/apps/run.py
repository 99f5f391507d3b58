"""``omnibot run``: several front ends on one runtime in one process (docs/architecture.md).

::

    omnibot run [ROBOT OPTIONS] [--teleop pad|keyboard] [--dashboard [--host ...]] [--follow PATH.csv]
                [--ros2 [--namespace NS]]

Each option adds a source (the pad or keyboard at priority 200, the page's stick and keys at 100,
ROS 2's cmd_vel at 90, the follower at 10) or a front end (the dashboard, whose link thread then runs the runtime) to one
:class:`~omnibot.runtime.runtime.Runtime`; the controller is left as it was found on every way out.
Imports here are light: :func:`add_arguments` runs whenever ``omnibot`` builds its parser.
"""

from __future__ import annotations

import argparse
import contextlib
import math
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from omnibot.errors import ConfigError

PAD_PRIORITY = 200
"""A person at the robot (pad, keyboard) outranks the page (100) and the follower (10)."""


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Declare ``omnibot run``'s options (the robot options shared with every command, then its own)."""
    from omnibot.apps.dashboard import add_server_options
    from omnibot.apps.ros2 import add_bridge_options
    from omnibot.cliargs import (
        add_calibration_option,
        add_off_path_option,
        add_robot_options,
        add_wheel_loop_option,
    )

    add_robot_options(
        p,
        world="room",
        port_help="the simulated --robot: in lockstep, or paced to the wall clock with --teleop or --dashboard",
    )
    p.add_argument(
        "--teleop",
        choices=("pad", "keyboard"),
        help="drive with a gamepad (pygame) or this terminal's keys, with the deadman (priority 200)",
    )
    p.add_argument(
        "--dashboard", action="store_true", help="serve the dashboard (its stick and keys: priority 100)"
    )
    add_server_options(p, "--dashboard: ")
    p.add_argument(
        "--follow",
        metavar="PATH.csv",
        help="follow a path file (priority 10); the robot is taken to stand at its first pose",
    )
    p.add_argument(
        "--follower", default="tracker", help="--follow: seed002, pure_pursuit or tracker (default)"
    )
    p.add_argument("--speed", type=float, help="--follow: speed cap, m/s (default: the robot's limit)")
    add_off_path_option(p, "--follow: ")
    p.add_argument(
        "--ros2",
        action="store_true",
        help="ROS 2 on DDS: cmd_vel (priority 90) in; odom, tf, imu, ranges, joint_states out",
    )
    add_bridge_options(p)
    p.add_argument(
        "--config", metavar="FILE.yaml", help="teleop parameters (pad mapping, rate; default seed 003's)"
    )
    add_wheel_loop_option(p)
    add_calibration_option(p)
    p.add_argument(
        "--duration",
        type=float,
        metavar="S",
        help="run for S seconds (default: until Ctrl-C, or the follow's end)",
    )


def _say(text: str) -> None:
    print(f"run: {text}", flush=True)


@dataclass
class Parts:
    """What ``run`` added to the runtime, and how to end it."""

    follower: Any = None
    judge: Any = None
    """The follower's judge (:class:`~omnibot.navigation.judge.FollowJudge`)."""
    printer: Any = None
    pad: Any = None
    device: Any = None
    lost: str | None = None
    """Why the dashboard's robot link ended (None: it did not)."""
    closers: list[Callable[[], object]] = field(default_factory=list)

    def close(self) -> None:
        """Release the input devices opened for the run (errors ignored: this runs on the way out)."""
        for close in reversed(self.closers):
            with contextlib.suppress(Exception):
                close()


def _check(args: argparse.Namespace) -> None:
    from omnibot.apps.ros2 import check as check_ros2
    from omnibot.cliargs import off_path_options
    from omnibot.control import follower_names

    if not (args.teleop or args.dashboard or args.follow or args.ros2):
        raise ConfigError("nothing to run: give --teleop, --dashboard, --follow and/or --ros2")
    check_ros2(args)
    if args.duration is not None and not (math.isfinite(args.duration) and args.duration > 0):
        raise ConfigError(f"expected a positive number of seconds, got {args.duration}", key="--duration")
    if args.speed is not None and not (math.isfinite(args.speed) and args.speed > 0):
        raise ConfigError(f"expected a positive speed in m/s, got {args.speed}", key="--speed")
    off_path_options(args)  # checked before anything starts
    if args.follower not in follower_names():
        raise ConfigError(
            f"unknown follower '{args.follower}'; expected one of: {', '.join(follower_names())}",
            key="--follower",
        )


def compose(
    runtime: Any,
    robot: Any,
    args: argparse.Namespace,
    config: Any,
    path: Any,
    say: Callable[[str], None] = _say,
) -> Parts:
    """Add the pad and the follower to ``runtime`` (any thread: before it runs); ``say`` tells the
    command's status lines."""
    from omnibot.apps.teleop import open_source
    from omnibot.cliargs import calibrated_floor, off_path_options
    from omnibot.estimation import make_estimator
    from omnibot.motion import Pose2D
    from omnibot.navigation import FOLLOWER_PRIORITY, STANDSTILL, FollowJudge, follower_source
    from omnibot.runtime import EstimatorWhenMissing, NoticePrinter, SpeedReport, StallWatch, Standstill
    from omnibot.teleop import PadSource, TwistLimits
    from omnibot.transport import find_simulator

    parts = Parts()
    if path is not None:
        slip = runtime.slip.params if runtime.slip is not None else None
        runtime.estimator = make_estimator("fused", robot, Pose2D(*path.start), slip)
        parts.follower = follower_source(
            robot, path, runtime.period, args.follower, args.speed, options=off_path_options(args)
        )
        runtime.add_source(parts.follower)
        parts.judge = FollowJudge(
            runtime, robot, parts.follower, speed=args.speed, on_verdict=lambda r: _tell(runtime, r)
        )
        # wheels that turn while the body does not: stop, say so (the simulator's truth a witness too)
        StallWatch.on(runtime, robot, truth=find_simulator(runtime.client.link))
        # as `omnibot follow`: the follower waits while the gyro's bias is learned (a person may drive)
        Standstill(runtime, STANDSTILL, FOLLOWER_PRIORITY)
        say(f"the follower stands still {STANDSTILL:g} s first, while the gyro's bias is learned")
    if args.teleop:
        flags = argparse.Namespace(keyboard=args.teleop == "keyboard", joystick=args.teleop == "pad")
        device = open_source(flags, config, say, ("--teleop keyboard", "--teleop pad"))
        parts.closers.append(device.close)
        if hasattr(device, "__enter__"):
            device.__enter__()
            parts.closers.append(lambda: device.__exit__(None, None, None))
        parts.device = device
        limits = TwistLimits.from_limits(runtime.client.limits, config, robot, calibrated_floor(args))
        parts.pad = PadSource(device, config, limits, name=args.teleop, priority=PAD_PRIORITY)
        runtime.add_source(parts.pad)
    if args.ros2 and getattr(args, "ros2_node", None) is None:  # (omnibot map attaches its own)
        from omnibot.apps.ros2 import attach_bridge

        node = attach_bridge(runtime, robot, args)
        parts.closers.append(node.close)
    parts.printer = NoticePrinter(say, control=True)
    runtime.add_sink(parts.printer)
    EstimatorWhenMissing.add(runtime, robot)  # the achieved twist of the status lines
    runtime.add_sink(SpeedReport(say))
    return parts


def outcome(report: dict[str, Any]) -> list[str]:
    """The follow's outcome and accuracy in ``omnibot follow``'s words: its summary, its verdict."""
    from omnibot.navigation import summary, verdict

    return [f"follow: {summary(report)}", f"follow {verdict(report)}"]


def _tell(runtime: Any, report: dict[str, Any]) -> None:
    """Every front end hears the verdict (the page's log, ROS 2's, the status lines)."""
    for line in outcome(report):
        runtime.notify("info" if report["completed"] else "warn", line, "follower")


def run(args: argparse.Namespace) -> int:
    """``omnibot run``: compose the front ends, run them, return the exit status."""
    from omnibot.cliargs import check_sim_options, sim_url
    from omnibot.control import read_path
    from omnibot.teleop import load_teleop_config

    _check(args)
    check_sim_options(args)
    config = load_teleop_config(args.config)
    url = sim_url(args)
    try:
        path = read_path(args.follow) if args.follow else None
    except (OSError, ValueError) as exc:
        raise ConfigError(f"cannot read {args.follow}: {exc}", key="--follow") from None
    if args.dashboard:
        parts = _with_dashboard(args, url, config, path)
    else:
        parts = run_in_this_thread(args, url, config, path)
    return _result(parts)


def _result(parts: Parts) -> int:
    if parts.lost is not None:
        print(f"omnibot run: the robot link ended: {parts.lost}", file=sys.stderr)
        return 1
    if parts.judge is None:
        return 0
    report = parts.judge.verdict()  # given at the follow's end, or now (the run ended first)
    said = {n.text for n in parts.printer.seen} if parts.printer is not None else set()
    for line in outcome(report):
        if line not in said:
            _say(line)
    return 0 if report["completed"] else 1


Attach = Callable[[Any, Any], list[Callable[[], object]]]
"""Adds a command's own sinks to the runtime before the front ends: ``attach(runtime, session)``
returns what to close when the run ends (``omnibot map`` adds its SLAM this way)."""


def run_in_this_thread(
    args: argparse.Namespace,
    url: str,
    config: Any,
    path: Any,
    attach: Attach | None = None,
    say: Callable[[str], None] = _say,
    frame: Callable[[], Any] | None = None,
) -> Parts:
    """``run``'s front ends (and ``attach``'s sinks) on one runtime in this thread (no dashboard);
    ``frame``: the follower steers in it (:class:`~omnibot.runtime.sources.FollowerSource`'s, a
    SLAM's ``map -> odom``)."""
    from omnibot.cliargs import recording_of, use_calibration
    from omnibot.client import robot_session
    from omnibot.ros2 import PERIOD as ROS2_PERIOD
    from omnibot.runtime import Runtime, start_sonars

    person = bool(args.teleop)
    wall = person or args.ros2  # a person or ROS 2 nodes: paced to the wall clock
    period = config.period if person else ROS2_PERIOD if args.ros2 else 0.01
    recording = recording_of(args)
    with robot_session(url, args.robot, timeout=max(0.2, config.vel_timeout), recording=recording) as session:
        client, robot = session.client, session.robot
        runtime = Runtime(
            client,
            period=period,
            vel_timeout=config.vel_timeout,
            wheel_loop=not args.open_loop,
            slip=use_calibration(args, client, robot),
            recording=recording,
        )
        if path is not None:
            start_sonars(client, robot)  # the stall watch's witnesses of what is ahead
        attached = attach(runtime, session) if attach is not None else []
        try:
            parts = compose(runtime, robot, args, config, path, say)
        except BaseException:
            Parts(closers=attached).close()
            raise
        parts.closers.extend(attached)
        if parts.follower is not None:
            parts.follower.frame = frame
        if path is not None:
            parts.closers.append(lambda: start_sonars(client, robot, 0.0))  # left not pinging, as found
        try:
            _drive(runtime, parts, period, person=person, wall=wall, duration=args.duration)
        finally:
            _stop_pad(runtime, parts, config)
            runtime.close()
            parts.close()
    return parts


def _drive(
    runtime: Any, parts: Parts, period: float, *, person: bool, wall: bool, duration: float | None
) -> None:
    """Start ``runtime`` and run it until the pad quits, the follow is judged (not when ``wall``:
    a person or ROS 2 nodes end it) or ``duration`` s pass. Binary unless a ``person`` drives, TEL
    every ``period`` (at least 10 ms); paced to the wall clock when ``wall``, else to the link's."""
    from omnibot.client import NotSupported
    from omnibot.protocol import codes
    from omnibot.runtime import LinkPacer
    from omnibot.teleop import Pacer

    client = runtime.client
    runtime.start()
    if not person:
        with contextlib.suppress(NotSupported):
            client.use_binary()
    client.telemetry(period if period >= 0.01 else 0.01, codes.TEL_MASK)
    # the schedule starts now (a person's input is paced to the wall clock, a follow alone
    # to the link's: lockstep on sim://)
    runtime.pacer = Pacer(client, period) if wall else LinkPacer(client, period)
    judge = parts.judge
    device = parts.device

    def done() -> bool:
        if device is not None and device.quit:
            return True
        return judge is not None and judge.report is not None and not wall

    runtime.run(until=done, duration=duration)


def _stop_pad(runtime: Any, parts: Parts, config: Any) -> None:
    """The pad's stop sequence when it was driving (as teleop ends)."""
    pad = parts.pad
    if pad is None or runtime.client.link.closed:
        return
    pad.closing = True
    for _ in range(config.stop_repeats):
        runtime.step()
        if pad.action.twist is None:
            break
        runtime.wait()


def _with_dashboard(args: argparse.Namespace, url: str, config: Any, path: Any) -> Parts:
    from omnibot.apps.dashboard import server_options
    from omnibot.cliargs import calibrated_floor, recording_of, use_calibration
    from omnibot.navigation import PathTeacher
    from omnibot.robot import RobotDescription
    from omnibot.web import Dashboard

    server = server_options(args)

    def make_teach(robot: RobotDescription) -> PathTeacher:
        return PathTeacher(robot, period=config.period)

    dash = Dashboard(
        url,
        args.robot,
        config=config,
        make_teach=None if path is not None else make_teach,  # a --follow path owns the estimator's frame
        wheel_loop=not args.open_loop,
        floor=lambda client, robot: use_calibration(args, client, robot),
        recording=recording_of(args),
        surface=calibrated_floor(args),
        **server,
    )
    parts = Parts()
    try:
        parts = compose(dash.link.runtime, dash.link.robot, args, config, path)
        dash.start()
        _say(f"dashboard for {url}: {dash.url}")
        if dash.token and not server["token"]:
            _say("(an access token was made up because the server is reachable from other machines)")
        _say("Ctrl-C stops it (and the robot)")
        end = math.inf if args.duration is None else time.monotonic() + args.duration
        while time.monotonic() < end and dash.link.alive:
            if parts.device is not None and parts.device.quit:
                break
            time.sleep(min(0.1, max(0.0, end - time.monotonic())))
        parts.lost = dash.link.lost
    finally:
        dash.stop()
        parts.close()
    return parts
