"""One leg of a goto: its plan on the map with what was met marked (:func:`plan_leg`), its heading
(:func:`leg_heading`), the follow with its obstacle watch (:class:`Leg`), and what ends it: an obstacle
the map did not have (:func:`obstacle_met`), the robot carried off the path (:func:`strayed`: a re-plan
from where it is, as for an obstacle) or where the robot settled (:func:`judge_leg`). The steps
:func:`~omnibot.navigation.goto.go_to` runs in a loop and
:class:`~omnibot.navigation.goto_source.GotoSource` takes cycle by cycle.
"""

from __future__ import annotations

import math
from typing import Literal

from omnibot.control import time_optimal_profile
from omnibot.errors import PlanningError
from omnibot.mapping import CostMap, PlannedPath, compose, inflate, inverse, plan_path
from omnibot.motion import Pose2D, Twist
from omnibot.navigation.brake import BrakeSource, coast_excess
from omnibot.navigation.following import FOLLOWER_PRIORITY, follower_source
from omnibot.navigation.goal import (
    FloatArray,
    GotoOptions,
    GotoResult,
    Outcome,
    PoseProvider,
    ScanSource,
    within,
)
from omnibot.navigation.obstacles import ObstacleWatch
from omnibot.navigation.planned import mark, planned_path, transformed
from omnibot.navigation.session import follower_limits
from omnibot.robot import RobotDescription
from omnibot.runtime import LinkPacer, Runtime, StallWatch


def leg_heading(
    robot: RobotDescription, opts: GotoOptions, scan: ScanSource | None
) -> Literal["travel", "goal"]:
    """The options' heading, ``auto`` resolved: travel when the robot has a sonar and no scan watches."""
    if opts.heading != "auto":
        return opts.heading
    return "travel" if robot.sonars and scan is None else "goal"


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
    if _spent(result, result.replans, "blocked", f"blocked: {why}", opts):
        return True
    result.replans += 1
    return False


def strayed(result: GotoResult, why: str, opts: GotoOptions) -> bool:
    """A leg ended with the robot farther from its path than the follower chases (``why``): True
    when the goto is over (``off path``: no re-plan left), else a re-plan from where the robot now is
    is due (counted in ``result.strays``)."""
    if _spent(result, result.strays, "off path", why, opts):
        return True
    result.strays += 1
    return False


def _spent(result: GotoResult, made: int, outcome: Outcome, why: str, opts: GotoOptions) -> bool:
    """True when the ``made`` re-plans are all the goto may make: it is over (``outcome``, ``why``)."""
    if made < opts.max_replans:
        return False
    result.outcome = outcome
    result.reason = f"{why}, still after {made} re-plans"
    return True


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
        self.robot = robot
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
        limits = follower_limits(robot, opts.speed)
        profile = time_optimal_profile(self.path, limits, use_path_speed=False)
        self.watch = ObstacleWatch(
            robot,
            cmap,
            self.path,
            provider,
            self._obstacle,
            lookahead=opts.lookahead,
            scan=scan,
            speed_at=profile.speed_at,
        )
        self.budget = 3.0 * profile.min_time + 10.0

    def _brake(self, runtime: Runtime) -> None:
        """Bring the robot to rest from the twist the follower last asked (:class:`BrakeSource`),
        the runtime cycling: braked on the motors where a coast would carry it farther than the
        margin beyond that, else the motors cut (STOP) and the coast waited out; a leg that an
        obstacle ended, that the robot was carried off, timed out or completed, not one ended by
        a failure (a stall, a refused
        command, an emergency stop: the caller's STOP cuts at once)."""
        source = self.source
        last = source.twist or Twist()
        cut = coast_excess(self.robot, math.hypot(last.vx, last.vy)) <= self.opts.margin
        if cut:
            runtime.client.stop()
        brake = BrakeSource(
            self.robot,
            last,
            runtime.period,
            priority=source.priority,
            watchdog=source.watchdog,
            cut=cut,
        )
        runtime.add_source(brake)
        try:
            runtime.run(until=lambda: brake.finished)
        finally:
            runtime.remove_source(brake.name)

    @property
    def off_path(self) -> bool:
        """The follower gave the leg up: the robot was farther from the path than it chases."""
        return self.source.follower.strayed is not None

    def _obstacle(self, why: str) -> None:
        self.why = why
        self.source.end(why)

    def run(
        self, runtime: Runtime, deadline: float, stalls: StallWatch
    ) -> Outcome | Literal["obstacle", "done"]:
        """Follow until the end, an obstacle, the robot off the path (``off path``), a failure or the
        time is up; then stop and settle."""
        client, source = runtime.client, self.source
        began = client.clock.now()
        end = min(deadline, began + (self.budget if self.opts.timeout is None else math.inf))
        found = len(stalls.stalls)
        runtime.pacer = LinkPacer(client, runtime.period)  # the schedule starts now
        runtime.add_source(source)
        runtime.add_sink(self.watch)
        try:
            runtime.run(until=lambda: source.finished or client.clock.now() > end)
            runtime.remove_source(source.name)
            runtime.remove_sink(self.watch)
            if self.watch.points is not None or self.off_path or not source.failure:
                self._brake(runtime)
        finally:
            runtime.remove_source(source.name)
            runtime.remove_sink(self.watch)
            runtime.discard_pending()
            if not client.link.closed and not runtime.latched:
                client.stop()
        runtime.run(duration=self.opts.settle)  # cycling: the estimate and the localiser see the rest
        if self.watch.points is not None:
            return "obstacle"
        if len(stalls.stalls) > found:
            self.why = stalls.stalls[-1].text
            return "stalled"
        if self.off_path:
            self.why = source.failure
            return "off path"
        if source.failure:
            self.why = source.failure
            return "stopped"
        if not source.finished:
            self.why = f"timed out: the leg was not done {client.clock.now() - began:.1f} s after it began"
            return "timed out"
        return "done"
