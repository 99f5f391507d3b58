"""Going to a place on a map: plan, follow with the tracker, stop for what the map lacks, re-plan.

::

    pose provider (map frame; default the runtime's estimate, later a localiser)
      -> plan_path on the map inflated by the robot's radius + margin (mapping.planner)
      -> a Path (map frame; the body faces its travel when a sonar looks ahead, else it turns
         towards the goal's heading as it goes) moved into the estimate's frame
      -> the runtime's follower source (navigation.following: the tracker on its time-optimal profile)
      -> every cycle an ObstacleWatch: sonar ranges (TEL) and an optional scan (map-frame points)
         that the map does not explain, in the robot's swept corridor ahead -> the leg ends, the
         robot is braked to rest (:mod:`omnibot.navigation.brake`, the runtime cycling), the
         points are marked in a copy of the grid, and it re-plans (bounded)
      -> the robot carried farther from the path than the follower chases (a push, a localiser's
         correction: :data:`~omnibot.control.followers.base.OFF_PATH`) -> the follower stops, the
         robot is braked to rest and it re-plans from where it is (bounded: ``off path``)
      -> at the path's end, settled: within ``aim`` (half) of ``tolerance`` and
         ``heading_tolerance`` of the goal (by the provider) -> arrived; else a correction leg from
         where it stands (bounded), and at the last the whole tolerances decide

:func:`go_to` drives a runtime that is already running (an estimator, telemetry with the sonars'
ranges), the same steps as :class:`~omnibot.navigation.goto_source.GotoSource` takes cycle by cycle
on a runtime a front end runs (:mod:`omnibot.navigation.leg`: ``Leg``, ``plan_leg``, ``obstacle_met``,
``strayed``, ``judge_leg``); :func:`goto` is the whole command on a client (the CLI's entry point): it starts
telemetry and the sonars, stands still while the gyro's bias is learned, goes, and leaves the
controller stopped. A goal off the map or where the robot cannot stand raises (OffMapError,
BlockedError: bad arguments) before anything moves; otherwise either returns a
:class:`~omnibot.navigation.goal.GotoResult` (:mod:`omnibot.navigation.goal`): ``arrived`` or why not (``outcome``: no path, blocked, timed out, stalled,
stopped, missed, off path) in one line (``reason``).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager, suppress
from typing import Literal

from omnibot.client import NotSupported, RobotClient
from omnibot.errors import ConfigError
from omnibot.estimation import SlipModel, make_estimator
from omnibot.mapping import (
    OccupancyGrid,
    check_goal,
    inflate,
)
from omnibot.motion import Pose2D
from omnibot.navigation.goal import (
    GotoOptions,
    GotoResult,
    Outcome,
    PoseProvider,
    ScanSource,
    within,
)
from omnibot.navigation.leg import Leg, judge_leg, leg_heading, obstacle_met, plan_leg, strayed
from omnibot.navigation.runner import STANDSTILL
from omnibot.protocol import codes
from omnibot.robot import RobotDescription
from omnibot.runtime import Cycle, Runtime, RuntimeRecording, StallWatch, start_sonars
from omnibot.transport import find_simulator

# --------------------------------------------------------------------------- going


def go_to(
    runtime: Runtime,
    robot: RobotDescription,
    grid: OccupancyGrid,
    goal: Pose2D,
    options: GotoOptions | None = None,
    *,
    pose: PoseProvider | None = None,
    scan: ScanSource | None = None,
) -> GotoResult:
    """Go to ``goal`` (map frame) on ``grid`` through a running ``runtime`` (it has an estimator
    and telemetry; with the sonars' ranges in it for the sonar watch). ``pose`` gives the map-frame
    pose (default: the runtime's estimate, the map frame being the estimator's); ``scan`` the
    latest scan's map-frame points. See the module docstring. A goal off the map or where the robot
    cannot stand (in a wall, in unknown space, too near a wall) raises OffMapError or BlockedError
    (both ConfigErrors: bad arguments) before anything moves; every other way of not arriving (no
    path, blocked on the way, timed out, stalled, stopped, missed) is the result's ``outcome``."""
    opts = options or GotoOptions()
    if runtime.estimator is None:
        raise ConfigError("goto needs a runtime with an estimator (the follower steers by it)")
    provider = pose or _estimate_pose(runtime)
    client = runtime.client
    clock = client.clock
    t0 = clock.now()
    heading = leg_heading(robot, opts, scan)
    radius = robot.footprint.bounding_radius
    _refuse_bad_goal(grid, goal, radius, opts)
    result = GotoResult(goal, "stopped", grid=grid)
    deadline = math.inf if opts.timeout is None else t0 + opts.timeout
    corrections = 0
    with _stall_watch(runtime, robot) as stalls:
        while True:
            here = _wait_pose(provider, runtime)
            result.final = here
            if not result.plans and within(here, goal, opts):  # there already
                result.outcome = "arrived"
                break
            planned = plan_leg(result, here, radius, opts)
            if planned is None:
                break
            est = runtime.estimate_now()
            assert est is not None
            leg = Leg(robot, *planned, here, est.pose, runtime.period, heading, opts, provider, scan)
            ended = leg.run(runtime, deadline, stalls)
            result.final = _wait_pose(provider, runtime)
            if ended != "done":
                if _leg_over(result, leg, ended, opts):
                    break
                continue
            if judge_leg(result, opts, corrections):
                break
            corrections += 1
    result.duration = clock.now() - t0
    return result


def _leg_over(result: GotoResult, leg: Leg, ended: Outcome | Literal["obstacle"], opts: GotoOptions) -> bool:
    """After a leg that did not reach its end: True when the goto is over (``ended`` a failure, or the
    re-plans spent), False when a re-plan from where the robot is is due (an obstacle the map
    lacked, the robot carried off its path)."""
    if ended == "obstacle":
        assert leg.watch.points is not None
        return obstacle_met(result, leg.watch.points, leg.why, opts)
    if ended == "off path":
        return strayed(result, leg.why, opts)
    result.outcome, result.reason = ended, leg.why
    return True


def _refuse_bad_goal(grid: OccupancyGrid, goal: Pose2D, radius: float, opts: GotoOptions) -> None:
    """OffMapError or BlockedError for a goal off the map or where the robot cannot stand: a bad
    argument, refused before anything moves."""
    check_goal(inflate(grid, robot_radius=radius, margin=opts.margin, allow_unknown=opts.allow_unknown), goal)


@contextmanager
def _stall_watch(runtime: Runtime, robot: RobotDescription) -> Iterator[StallWatch]:
    """The runtime's stall watch, else one of the trip's own (closed after it)."""
    watch = StallWatch.of(runtime)
    if watch is not None:
        yield watch
        return
    own = StallWatch(runtime, robot, truth=find_simulator(runtime.client.link))
    try:
        yield own
    finally:
        own.close()


def _estimate_pose(runtime: Runtime) -> PoseProvider:
    def pose() -> Pose2D | None:
        est = runtime.estimate_now()
        return None if est is None else est.pose

    return pose


def _wait_pose(provider: PoseProvider, runtime: Runtime, limit: float = 2.0) -> Pose2D:
    """The provider's pose, cycling the runtime (nothing drives: its sinks, a localiser among them,
    see the telemetry) until it has one."""
    pose = provider()
    start = runtime.client.clock.now()
    while pose is None:
        if runtime.client.clock.now() - start > limit:
            raise ConfigError(f"goto: no pose of the robot after {limit:.0f} s (no telemetry?)")
        runtime.step()
        runtime.client.sleep(runtime.period)
        pose = provider()
    return pose


@contextmanager
def navigation_runtime(
    client: RobotClient,
    robot: RobotDescription,
    start: Pose2D,
    *,
    standstill: float = STANDSTILL,
    slip: SlipModel | None = None,
    sinks: Sequence[Callable[[Cycle], object]] = (),
    recording: RuntimeRecording | None = None,
) -> Iterator[Runtime]:
    """A runtime for going places (goto, exploring): the fused estimator starting at ``start``,
    binary where the controller speaks it, telemetry (encoders, heading, queue; tracking wheels and
    sonars where the robot has them) and the sonars started, ``sinks`` added, ``standstill`` s still
    for the gyro's bias, recorded in ``recording`` (``--log``); on the way out the controller is left
    stopped with telemetry and sonars off."""
    estimator = make_estimator("fused", robot, start, slip.params if slip is not None else None)
    runtime = Runtime(client, estimator=estimator, slip=slip, recording=recording)
    for sink in sinks:
        runtime.add_sink(sink)
    client.stop()
    period = 0.02
    with suppress(NotSupported):
        client.use_binary()
        period = 0.01
    mask = codes.TEL_ENCODERS | codes.TEL_HEADING | codes.TEL_QUEUE
    if robot.encoders.tracking:
        mask |= codes.TEL_TRACKING
    if robot.sonars:
        mask |= codes.TEL_SONAR
    runtime.period = period
    try:
        runtime.start()
        if robot.sonars:
            start_sonars(client, robot)
        client.telemetry(period, mask)
        client.sleep(standstill)
        yield runtime
    finally:
        try:
            if not client.link.closed:
                client.stop()
                if robot.sonars:
                    start_sonars(client, robot, 0.0)
                client.telemetry(0.0)
        finally:
            runtime.close()


def goto(
    client: RobotClient,
    robot: RobotDescription,
    grid: OccupancyGrid,
    goal: Pose2D,
    start: Pose2D,
    options: GotoOptions | None = None,
    *,
    pose: PoseProvider | None = None,
    pose_from: Callable[[Runtime], PoseProvider] | None = None,
    scan: ScanSource | None = None,
    standstill: float = STANDSTILL,
    slip: SlipModel | None = None,
    recording: RuntimeRecording | None = None,
) -> GotoResult:
    """``omnibot goto``: the robot standing at ``start`` (the estimator starts there: the map frame
    unless a provider says otherwise), on a :func:`navigation_runtime`, then :func:`go_to` with the
    map-frame pose from ``pose``, or from the provider ``pose_from`` makes on goto's runtime (a
    localiser fed by its telemetry and estimate), else the estimate; ``slip`` is the floor's
    calibrated wheel slip (``--calibration``: the runtime asks the wheels for the creep, the
    estimator takes it out); ``recording`` records the runtime (``--log``); the controller is left
    stopped with telemetry and sonars off."""
    with navigation_runtime(
        client, robot, start, standstill=standstill, slip=slip, recording=recording
    ) as runtime:
        provider = pose_from(runtime) if pose_from is not None else pose
        return go_to(runtime, robot, grid, goal, options, pose=provider, scan=scan)


__all__ = ["go_to", "goto", "navigation_runtime"]
