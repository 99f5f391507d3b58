"""Going to a place on a map: plan, follow with the tracker, stop for what the map lacks, re-plan.

::

    pose provider (map frame; default the runtime's estimate, later a localiser)
      -> plan_path on the map inflated by the robot's radius + margin (mapping.planner)
      -> a Path (map frame; the body faces its travel when a sonar looks ahead, else it turns
         towards the goal's heading as it goes) moved into the estimate's frame
      -> the runtime's follower source (navigation.following: the tracker on its time-optimal profile)
      -> every cycle an ObstacleWatch: sonar ranges (TEL) and an optional scan (map-frame points)
         that the map does not explain, in the robot's swept corridor ahead -> the leg ends, the
         robot stops, the points are marked in a copy of the grid, and it re-plans (bounded)
      -> at the path's end, settled: within ``aim`` (half) of ``tolerance`` and
         ``heading_tolerance`` of the goal (by the provider) -> arrived; else a correction leg from
         where it stands (bounded), and at the last the whole tolerances decide

:func:`go_to` drives a runtime that is already running (an estimator, telemetry with the sonars'
ranges), the same steps as :class:`~omnibot.navigation.goto_source.GotoSource` takes cycle by cycle
on a runtime a front end runs (:class:`Leg`, :func:`plan_leg`, :func:`obstacle_met`,
:func:`judge_leg`); :func:`goto` is the whole command on a client (the CLI's entry point): it starts
telemetry and the sonars, stands still while the gyro's bias is learned, goes, and leaves the
controller stopped. A goal off the map or where the robot cannot stand raises (OffMapError,
BlockedError: bad arguments) before anything moves; otherwise either returns a
:class:`GotoResult`: ``arrived`` or why not (``outcome``: no path, blocked, timed out, stalled,
stopped, missed) in one line (``reason``).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager, suppress
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from omnibot.client import NotSupported, RobotClient
from omnibot.control import Path, min_traversal_time, resample, wrap
from omnibot.errors import ConfigError, PlanningError
from omnibot.estimation import SlipModel, make_estimator
from omnibot.mapping import (
    MARGIN,
    OCCUPIED,
    CostMap,
    OccupancyGrid,
    PlannedPath,
    Planner,
    check_goal,
    compose,
    inflate,
    inverse,
    plan_path,
)
from omnibot.motion import Pose2D
from omnibot.navigation.following import FOLLOWER_PRIORITY, follower_source
from omnibot.navigation.runner import SETTLE, STANDSTILL
from omnibot.navigation.session import follower_limits
from omnibot.protocol import codes
from omnibot.robot import RobotDescription
from omnibot.runtime import Cycle, LinkPacer, Runtime, RuntimeRecording, StallWatch, start_sonars
from omnibot.transport import find_simulator

FloatArray = NDArray[np.float64]
PoseProvider = Callable[[], Pose2D | None]
"""The robot's pose in the map frame now (None: not known yet)."""
ScanSource = Callable[[], FloatArray | None]
"""The latest scan's points (n, 2) in the map frame (None: no scan yet)."""
Outcome = Literal["arrived", "no path", "blocked", "timed out", "stalled", "stopped", "missed", "cancelled"]
Heading = Literal["auto", "travel", "goal"]

SPACING = 0.05
"""m between the path's points (the tracker's profile interpolates between them)."""
SHORTEST = 0.01
"""m: a shorter leg (a turn in place, a last correction) goes this far out along the heading and back."""
TRAVEL_LEAST = 0.3
"""m: a shorter leg (a correction) turns towards the goal's heading on the way even in ``travel``."""
EXPLAINED = 0.10
"""m: a range reading this close to a wall of the map is that wall."""
ARC_STEP = math.radians(2.5)
"""rad between the points a sonar reading marks across its cone."""


@dataclass(frozen=True)
class GotoOptions:
    """How to go: tolerances of arrival, the planner's, speed, heading, and the obstacle watch."""

    tolerance: float = 0.05
    """m from the goal's position to count as arrived."""
    heading_tolerance: float = math.radians(5.0)
    """rad from the goal's heading to count as arrived."""
    margin: float = MARGIN
    """m kept free beyond the robot's radius (the footprint's bounding circle)."""
    allow_unknown: bool = False
    """Plan through unknown cells (else they are walls)."""
    planner: Planner = "grid"
    speed: float | None = None
    """Speed cap, m/s (None: the robot's own limits)."""
    heading: Heading = "auto"
    """``travel``: the body faces where it goes (turning in place at corners and at the end),
    so a front sonar looks ahead; ``goal``: it turns towards the goal's heading along the way;
    ``auto``: travel when the robot has a sonar and no scan is given, else goal."""
    lookahead: float = 1.0
    """m of the path ahead watched for obstacles the map does not have."""
    max_replans: int = 5
    """Re-plans after obstacles before giving up (blocked)."""
    corrections: int = 2
    """Short legs from where the robot stopped when it ended farther than ``aim`` of the tolerances."""
    aim: float = 0.5
    """The fraction of the tolerances a leg's end must meet not to take a correction leg (arrival
    itself is judged at the whole tolerances, once the corrections are spent)."""
    timeout: float | None = None
    """s for the whole goto (None: three times each leg's minimum time plus 10 s per leg)."""
    settle: float = SETTLE
    """s to wait after each leg's stop before the pose is read."""

    def __post_init__(self) -> None:
        for name in ("tolerance", "heading_tolerance", "lookahead"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise ConfigError(f"goto's {name} must be a positive number, not {value}")
        if not 0 < self.aim <= 1:
            raise ConfigError(f"goto's aim must be a fraction in (0, 1], not {self.aim}")
        if self.max_replans < 0 or self.corrections < 0:
            raise ConfigError("goto's max_replans and corrections must be >= 0")


@dataclass
class GotoResult:
    """What a goto did: ``arrived`` or why not (``outcome``, ``reason``), where it ended."""

    goal: Pose2D
    outcome: Outcome
    reason: str = ""
    """One line saying why it did not arrive ("" when it did)."""
    final: Pose2D | None = None
    """The provider's pose at the end (map frame)."""
    plans: list[PlannedPath] = field(default_factory=list)
    replans: int = 0
    """Plans made after an obstacle the map did not have."""
    obstacles: list[tuple[float, float]] = field(default_factory=list)
    """Map-frame points marked as obstacles on the way."""
    grid: OccupancyGrid | None = None
    """The map with those obstacles marked."""
    duration: float = 0.0
    """s on the link's clock from the start to the end."""

    @property
    def arrived(self) -> bool:
        """Within the tolerances at the end."""
        return self.outcome == "arrived"

    @property
    def error(self) -> float:
        """m from the goal at the end (nan without a final pose)."""
        f = self.final
        return math.nan if f is None else math.hypot(f.x - self.goal.x, f.y - self.goal.y)

    @property
    def heading_error(self) -> float:
        """rad from the goal's heading at the end (nan without a final pose)."""
        f = self.final
        return math.nan if f is None else abs(wrap(f.theta - self.goal.theta))

    def summary(self) -> str:
        """One line for a terminal."""
        where = (
            ""
            if self.final is None
            else f" ({100 * self.error:.1f} cm, {math.degrees(self.heading_error):.1f} degrees from the goal)"
        )
        if self.arrived:
            return f"arrived at ({self.goal.x:.2f}, {self.goal.y:.2f}){where}"
        return f"did not arrive: {self.reason}{where}"


# --------------------------------------------------------------------------- paths and frames


def transformed(path: Path, t: Pose2D) -> Path:
    """``path`` with every pose moved by ``t`` (``t`` o pose)."""
    c, s = math.cos(t.theta), math.sin(t.theta)
    return Path(
        t.x + c * path.x - s * path.y, t.y + s * path.x + c * path.y, path.theta + t.theta, path.t, path.v
    )


def planned_path(plan: PlannedPath, start_theta: float, heading: Literal["travel", "goal"]) -> Path:
    """The project's path type for a plan: ``goal`` turns the heading from ``start_theta`` to the
    goal's in proportion to the distance covered; ``travel`` faces each straight run (turning in
    place before it) and turns in place to the goal's heading at the end. Resampled every
    :data:`SPACING` m (corners and turns in place kept). A plan shorter than :data:`SHORTEST` (a
    turn in place) goes that far out along the heading and back, turning on the way."""
    pts = plan.waypoints
    goal_theta = start_theta + wrap(plan.theta - start_theta)
    if plan.length < SHORTEST:  # the tracker needs a length: out along the heading and back
        ahead = pts[0] + SHORTEST * np.array([math.cos(start_theta), math.sin(start_theta)])
        pts = np.vstack([pts[:1], ahead, pts[-1:]])
        heading = "goal"
    if heading == "goal" or plan.length < TRAVEL_LEAST:
        s = np.concatenate(([0.0], np.cumsum(np.hypot(*np.diff(pts, axis=0).T))))
        theta = start_theta + (goal_theta - start_theta) * s / s[-1]
        return resample(Path(pts[:, 0].copy(), pts[:, 1].copy(), theta), SPACING)
    xs, ys, th = [float(pts[0, 0])], [float(pts[0, 1])], [start_theta]
    current = start_theta
    for a, b in itertools.pairwise(pts):
        if math.hypot(float(b[0] - a[0]), float(b[1] - a[1])) < 1e-9:
            continue
        course = math.atan2(float(b[1] - a[1]), float(b[0] - a[0]))
        current = current + wrap(course - current)
        xs.append(float(a[0]))  # turn in place to face the run
        ys.append(float(a[1]))
        th.append(current)
        xs.append(float(b[0]))
        ys.append(float(b[1]))
        th.append(current)
    xs.append(float(pts[-1, 0]))
    ys.append(float(pts[-1, 1]))
    th.append(current + wrap(plan.theta - current))
    return resample(Path(np.array(xs), np.array(ys), np.array(th)), SPACING)


def mark(grid: OccupancyGrid, points: FloatArray) -> OccupancyGrid:
    """A copy of ``grid`` with the cells holding ``points`` (map frame, on the grid) occupied."""
    data = grid.data.copy()
    cells = grid.world_to_cell(points)
    cells = cells[grid.inside(cells)]
    data[cells[:, 0], cells[:, 1]] = OCCUPIED
    return OccupancyGrid(data, grid.resolution, grid.origin, grid.frame)


# --------------------------------------------------------------------------- the obstacle watch


class ObstacleWatch:
    """A sink: ends ``leg`` when a sonar reading or a scan point that ``cmap``'s walls do not
    explain (none within :data:`EXPLAINED`) lies in the robot's corridor (radius + margin either
    side) on the next ``lookahead`` m of ``path`` (map frame); :attr:`points` are then what to mark."""

    def __init__(
        self,
        robot: RobotDescription,
        cmap: CostMap,
        path: Path,
        pose: PoseProvider,
        stop: Callable[[str], object],
        *,
        lookahead: float,
        scan: ScanSource | None = None,
    ) -> None:
        self.robot = robot
        self.cmap = cmap
        self.path = path
        self.pose = pose
        self.stop = stop
        self.lookahead = lookahead
        self.scan = scan
        self.points: FloatArray | None = None
        """The unexplained points that ended the leg (None: none did)."""
        self._s = 0.0

    def __call__(self, cycle: Cycle) -> None:
        """Look at this cycle's sonar ranges and the latest scan."""
        if self.points is not None:
            return
        pose = self.pose()
        if pose is None:
            return
        if len(self.path) > 1:
            self._s = self.path.project_near(pose.x, pose.y, self._s, behind=0.1, ahead=0.5).s
        clouds = [(self._sonar_points(pose, r), True) for r in self._ranges(cycle)]
        if self.scan is not None:
            scan = self.scan()
            if scan is not None and len(scan):
                clouds.append((np.asarray(scan, dtype=np.float64).reshape(-1, 2), False))
        for cloud, sonar in clouds:
            new = self._unexplained(cloud, sonar=sonar)
            if new is not None and self._ahead(new):
                self.points = new
                x, y = np.mean(new, axis=0)
                self.stop(f"an obstacle the map does not have at ({x:.2f}, {y:.2f})")
                return

    def _ranges(self, cycle: Cycle) -> list[tuple[int, float]]:
        """(sonar index, range) of the newest telemetry sample's readings within range."""
        for tel in reversed(cycle.telemetry):
            if tel.ranges is None:
                continue
            out = []
            for k, r in enumerate(tel.ranges):
                if r is None or k >= len(self.robot.sonars):
                    continue
                sonar = self.robot.sonars[k]
                if sonar.min_range < r < sonar.max_range - 0.05:
                    out.append((k, r))
            return out
        return []

    def _sonar_points(self, pose: Pose2D, reading: tuple[int, float]) -> FloatArray:
        """The arc of points a reading says something lies on (map frame)."""
        sonar = self.robot.sonars[reading[0]]
        origin = compose(pose, Pose2D(sonar.x, sonar.y, sonar.angle))
        half = 0.5 * math.radians(sonar.cone_deg)
        n = max(2, math.ceil(2 * half / ARC_STEP) + 1)
        ang = origin.theta + np.linspace(-half, half, n)
        r = reading[1]
        return np.column_stack((origin.x + r * np.cos(ang), origin.y + r * np.sin(ang)))

    def _unexplained(self, cloud: FloatArray, *, sonar: bool) -> FloatArray | None:
        """The points no wall explains: for a sonar's arc, all of it when no point of it lies near
        a wall (the echo came from the nearest thing in the cone), else None; for a scan, each
        point on its own."""
        near = np.array([self.cmap.clearance_at(float(x), float(y)) < EXPLAINED for x, y in cloud])
        if sonar:
            return None if near.any() else cloud
        out = cloud[~near]
        return out if len(out) else None

    def _ahead(self, points: FloatArray) -> bool:
        """Whether any point lies in the corridor of the next ``lookahead`` m of the path."""
        if len(self.path) < 2:
            return False
        dist, s = self.path.nearest(points)
        ahead = (s >= self._s - 0.05) & (s <= self._s + self.lookahead)
        return bool(np.any(ahead & (dist < self.cmap.inflated)))


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
            if ended == "obstacle":
                assert leg.watch.points is not None
                if obstacle_met(result, leg.watch.points, leg.why, opts):
                    break
                continue
            if ended != "done":
                result.outcome = ended
                result.reason = leg.why
                break
            if judge_leg(result, opts, corrections):
                break
            corrections += 1
    result.duration = clock.now() - t0
    return result


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


def leg_heading(
    robot: RobotDescription, opts: GotoOptions, scan: ScanSource | None
) -> Literal["travel", "goal"]:
    """The options' heading, ``auto`` resolved: travel when the robot has a sonar and no scan watches."""
    if opts.heading != "auto":
        return opts.heading
    return "travel" if robot.sonars and scan is None else "goal"


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


def plan_leg(
    result: GotoResult, here: Pose2D, radius: float, opts: GotoOptions
) -> tuple[CostMap, PlannedPath] | None:
    """A plan from ``here`` to the goal on the result's grid (the map with what was met marked),
    inflated by ``radius`` + the margin, kept in ``result.plans``; None when there is none (the
    goto is over: ``no path``, or ``blocked`` after obstacles the map did not have)."""
    assert result.grid is not None
    cmap = inflate(result.grid, robot_radius=radius, margin=opts.margin, allow_unknown=opts.allow_unknown)
    try:
        plan = plan_path(cmap, here, result.goal, planner=opts.planner)
    except PlanningError as exc:
        result.outcome = "blocked" if result.replans else "no path"
        result.reason = str(exc) + (
            f" (after {result.replans} obstacle(s) the map did not have)" if result.replans else ""
        )
        return None
    result.plans.append(plan)
    return cmap, plan


def obstacle_met(result: GotoResult, points: FloatArray, why: str, opts: GotoOptions) -> bool:
    """A leg ended by ``points`` the map does not have: they are marked in the result's grid; True
    when the goto is over (``blocked``: no re-plan left), else a re-plan is due (counted)."""
    assert result.grid is not None
    result.obstacles.extend((float(x), float(y)) for x, y in points)
    result.grid = mark(result.grid, points)
    if result.replans >= opts.max_replans:
        result.outcome = "blocked"
        result.reason = f"blocked: {why}, still after {result.replans} re-plans"
        return True
    result.replans += 1
    return False


def judge_leg(result: GotoResult, opts: GotoOptions, corrections: int) -> bool:
    """After a leg that reached its end, with ``result.final`` where the robot settled: True when the
    goto is over (``arrived``, or ``missed`` once the ``corrections`` made are all it may make),
    False when a correction leg is due. Arrival is within ``aim`` of the tolerances, or within them
    once the corrections are spent."""
    final = result.final
    assert final is not None
    spent = corrections >= opts.corrections
    if within(final, result.goal, opts, opts.aim) or (spent and within(final, result.goal, opts)):
        result.outcome = "arrived"
        return True
    if spent:
        result.outcome = "missed"
        result.reason = "ended outside the tolerances" + (
            f" ({100 * opts.tolerance:.0f} cm, {math.degrees(opts.heading_tolerance):.0f} degrees)"
        )
        return True
    return False


def within(pose: Pose2D, goal: Pose2D, opts: GotoOptions, share: float = 1.0) -> bool:
    """``pose`` is within ``share`` of the tolerances of ``goal``."""
    return (
        math.hypot(pose.x - goal.x, pose.y - goal.y) <= share * opts.tolerance
        and abs(wrap(pose.theta - goal.theta)) <= share * opts.heading_tolerance
    )


class Leg:
    """One follow of one plan (map frame), started ``here`` (map frame) while the estimate the
    follower steers by is ``estimate``: the follower source (``name``, ``priority``) on the path moved
    into the estimate's frame, its obstacle watch, its time budget; :meth:`run` drives it on a
    runtime (:func:`go_to`), a :class:`~omnibot.navigation.goto_source.GotoSource` asks it cycle by
    cycle."""

    def __init__(
        self,
        robot: RobotDescription,
        cmap: CostMap,
        plan: PlannedPath,
        here: Pose2D,
        estimate: Pose2D,
        period: float,
        heading: Literal["travel", "goal"],
        opts: GotoOptions,
        provider: PoseProvider,
        scan: ScanSource | None,
        *,
        name: str = "goto",
        priority: int = FOLLOWER_PRIORITY,
    ) -> None:
        self.opts = opts
        self.path = planned_path(plan, here.theta, heading)
        # the map -> estimate transform now: the follower steers by the estimate
        self.to_estimate = compose(estimate, inverse(here))
        self.source = follower_source(
            robot,
            transformed(self.path, self.to_estimate),
            period,
            speed=opts.speed,
            name=name,
            priority=priority,
        )
        self.why = ""
        self.watch = ObstacleWatch(
            robot, cmap, self.path, provider, self._obstacle, lookahead=opts.lookahead, scan=scan
        )
        limits = follower_limits(robot, opts.speed)
        self.budget = 3.0 * min_traversal_time(self.path, limits) + 10.0

    def _obstacle(self, why: str) -> None:
        self.why = why
        self.source.end(why)

    def run(
        self, runtime: Runtime, deadline: float, stalls: StallWatch
    ) -> Outcome | Literal["obstacle", "done"]:
        """Follow until the end, an obstacle, a failure or the time is up; then stop and settle."""
        client, source = runtime.client, self.source
        began = client.clock.now()
        end = min(deadline, began + (self.budget if self.opts.timeout is None else math.inf))
        found = len(stalls.stalls)
        runtime.pacer = LinkPacer(client, runtime.period)  # the schedule starts now
        runtime.add_source(source)
        runtime.add_sink(self.watch)
        try:
            runtime.run(until=lambda: source.finished or client.clock.now() > end)
        finally:
            runtime.remove_source(source.name)
            runtime.remove_sink(self.watch)
            runtime.discard_pending()
            if not client.link.closed and not runtime.latched:
                client.stop()
        client.sleep(self.opts.settle)
        if self.watch.points is not None:
            return "obstacle"
        if len(stalls.stalls) > found:
            self.why = stalls.stalls[-1].text
            return "stalled"
        if source.failure:
            self.why = source.failure
            return "stopped"
        if not source.finished:
            self.why = f"timed out: the leg was not done {client.clock.now() - began:.1f} s after it began"
            return "timed out"
        return "done"


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


__all__ = [
    "GotoOptions",
    "GotoResult",
    "Leg",
    "ObstacleWatch",
    "PoseProvider",
    "ScanSource",
    "go_to",
    "goto",
    "judge_leg",
    "leg_heading",
    "mark",
    "navigation_runtime",
    "obstacle_met",
    "plan_leg",
    "planned_path",
    "within",
]
