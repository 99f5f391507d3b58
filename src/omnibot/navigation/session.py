"""One-call follow runs: open the simulated robot at the path's start, or drive any link.

:func:`simulated_client` builds the lockstep ``sim://`` link with the robot standing at a given pose
(so the path's frame and the simulator's coincide); :func:`follow_path` prepares a
:class:`~omnibot.navigation.runner.Navigator`, runs one follower and returns the run and its report.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Any

from omnibot.client import RobotClient
from omnibot.control import MotionLimits, Path, make_follower
from omnibot.estimation import SlipParameters
from omnibot.motion import Pose2D
from omnibot.navigation.metrics import follow_report
from omnibot.navigation.outcome import Tolerances
from omnibot.navigation.runner import GYRO_USE, STANDSTILL, Navigator
from omnibot.navigation.trace import FollowRun
from omnibot.progress import Progress
from omnibot.robot import RobotDescription
from omnibot.runtime import RuntimeRecording

DEFAULT_RATE = 100.0
"""Control rate of the follower loop, Hz."""
PLAN_FLOOR_USE = 0.95
"""The fraction of a floor's reach (:func:`omnibot.control.reach.floor_speed_table`) followers plan
with: the reach already carries the floor's load, so only the wheel loop's headroom is left."""


def follower_limits(
    robot: RobotDescription, speed: float | None = None, floor: str | None = None
) -> MotionLimits:
    """What followers may plan with: the robot's limits, the speed capped at ``speed`` (and, given a
    ``floor``, at its reach per course), and the turn rate kept inside 90 % of the gyro's range (a
    saturated gyro loses heading); the floor's reach at :data:`PLAN_FLOOR_USE`, and the course's
    turn rate within what the floor's sideways creep lets the odometry hold
    (:func:`~omnibot.control.reach.floor_course_rate`)."""
    limits = replace(MotionLimits.from_robot(robot, speed, surface=floor), floor_use=PLAN_FLOOR_USE)
    if floor is not None:
        from omnibot.control import floor_course_rate

        limits = replace(limits, course_rate=floor_course_rate(floor))
    if robot.gyro is not None:
        limits = limits.with_turn_rate(GYRO_USE * robot.gyro.range)
    return limits


def simulated_client(
    robot: RobotDescription,
    *,
    surface: str | None = None,
    seed: int = 0,
    start: Pose2D | None = None,
    world: str | None = None,
) -> RobotClient:
    """A client on the lockstep simulator (firmware + physics) with the robot standing at ``start``
    (None: at the world's own start, the origin in a world without one)."""
    from omnibot.sim import SimDevice
    from omnibot.transport import LockstepLink

    pose = None if start is None else (start.x, start.y, start.theta)
    device = SimDevice(robot, surface=surface, world=world, seed=seed, start_pose=pose)
    query = f"seed={seed}" + (f"&surface={surface}" if surface else "") + (f"&world={world}" if world else "")
    link = LockstepLink(device, url=f"sim://{robot.name}?{query}")
    return RobotClient(link, robot)


@dataclass
class FollowOptions:
    """How to follow: follower name and options, speed cap, estimator, control rate, wheel loop."""

    follower: str = "tracker"
    speed: float | None = None
    estimator: str = "fused"
    rate: float = DEFAULT_RATE
    wheel_loop: bool = True
    """Close the controller's wheel-speed loop (False: open loop, ``--open-loop``)."""
    follower_options: dict[str, Any] = field(default_factory=dict)
    observers: tuple[str, ...] = ()
    standstill: float = STANDSTILL
    calibrate_gyro: bool = False
    """Spin in place one turn each way at two rates first (the gyro's scale error is learned; the
    robot ends where it started, within its odometry)."""
    slip: SlipParameters | None = None
    """The floor's wheel slip (creep and distance scale) for the driven-wheel encoders, from
    ``omnibot calibrate``."""
    floor: str | None = None
    """Plan within this floor's reach per course (:func:`omnibot.control.reach.floor_speed_table`),
    and measure the time against the minimum on it; None: the motors' free-running speed only."""
    tolerances: Tolerances = field(default_factory=Tolerances)
    """What the run must achieve for its report to say ``completed``."""
    progress: Progress | None = None
    """A bar in metres that hears the distance covered (a terminal's, see :mod:`omnibot.progress`)."""
    recording: RuntimeRecording | None = None
    """The command's ``--log`` / ``--foxglove``: records the navigator's runtime."""


def follow_path(
    client: RobotClient, robot: RobotDescription, path: Path, options: FollowOptions | None = None
) -> tuple[FollowRun, dict[str, Any], Navigator]:
    """Follow ``path`` through ``client`` (the robot standing at the path's start); the run, its
    report (:func:`~omnibot.navigation.metrics.tracking_report`) and the navigator (for observers)."""
    opts = options or FollowOptions()
    limits = follower_limits(robot, opts.speed, opts.floor)
    follower = make_follower(opts.follower, limits, rate=opts.rate, **opts.follower_options)
    nav = Navigator(
        client,
        robot,
        estimator=opts.estimator,
        observers=opts.observers,
        wheel_loop=opts.wheel_loop,
        start=Pose2D(*path.start),
        slip=opts.slip,
        recording=opts.recording,
    )
    try:
        nav.prepare(opts.standstill)
        if opts.calibrate_gyro:
            nav.calibrate_gyro()
        run = nav.follow(path, follower, progress=opts.progress)
    finally:
        nav.close()
    report = follow_report(run, robot, opts.tolerances, speed=opts.speed, floor=opts.floor)
    report["rate_hz"] = opts.rate
    return run, report, nav


def simulate_follow(
    robot: RobotDescription,
    path: Path,
    options: FollowOptions | None = None,
    *,
    surface: str | None = None,
    seed: int = 0,
) -> tuple[FollowRun, dict[str, Any]]:
    """Follow ``path`` on the simulated ``robot`` (standing at the path's start) in lockstep."""
    start = Pose2D(*path.start)
    with simulated_client(robot, surface=surface, seed=seed, start=start) as client:
        run, report, _ = follow_path(client, robot, path, options)
    report["surface"] = surface or "wood"
    report["seed"] = seed
    return run, report


def summary(report: dict[str, Any]) -> str:
    """One line: RMS, max, time against the minimum, final error."""
    return (
        f"RMS {100 * report['rms_cross_track_m']:.2f} cm, max {100 * report['max_cross_track_m']:.2f} cm, "
        f"{report['duration_s']:.2f} s of minimum {report['min_time_s']:.2f} s "
        f"({report['time_ratio']:.2f}x), final error {100 * report['final_error_m']:.2f} cm"
        + ("" if report.get("completed", True) else ", NOT COMPLETED")
        + (f" [{report['source']}]" if not math.isnan(report["rms_cross_track_m"]) else "")
    )


def verdict(report: dict[str, Any]) -> str:
    """One line: completed within the tolerances (which), or NOT COMPLETED and why."""
    if not report["completed"]:
        return "NOT COMPLETED: " + "; ".join(report["failures"])
    tol = report["tolerances"]
    return (
        f"completed (within {100 * tol['final_m']:.1f} cm of the path's end, never more than "
        f"{100 * tol['cross_track_m']:.1f} cm off it)"
    )
