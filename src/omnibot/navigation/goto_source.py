"""goto as a runtime source: a goal gone to cycle by cycle on a runtime that a front end runs.

:func:`omnibot.navigation.goto.go_to` drives a runtime itself (``runtime.run`` for each leg); a front
end with a loop of its own (the ROS 2 bridge's ``goal_pose``) cannot hand its runtime over.
:class:`GotoSource` goes the same way as a source: :meth:`GotoSource.go` gives it a goal and the
runtime's cycles do the rest, each through :meth:`GotoSource.propose`::

    go(goal) -> checked on the map (OffMapError, BlockedError: refused, nothing changes)
    waiting   no pose yet (the localiser's first scan)          -> planning
    planning  plan_leg from the pose (no path: over)            -> leg
    leg       the tracker on the plan (leg.Leg), its ObstacleWatch asked each cycle;
              an obstacle -> marked, re-planned (bounded); the robot farther from the path than
              the follower chases -> re-planned from where it is (bounded); the time budget -> timed out;
              a stall, a refused command, an emergency stop -> stalled / stopped
    settling  braked to rest (navigation.brake: the leg's last twist ramped to zero at the
              robot's accelerations, then zero until the estimate is still), a zero twist for
              ``settle`` s, then the pose judged (leg.judge_leg): arrived | a correction leg | missed
    standby   another source (a person's cmd_vel, a pad) or a lock has the robot: the leg ends,
              a zero twist is proposed (ready to take the robot back) and, when the robot comes
              back to it, it plans again from where the robot then is

Every goal ends in one :class:`~omnibot.navigation.goal.GotoResult` handed to ``on_result``:
arrived, or why not; a new goal pre-empts the one being gone to (its result: ``cancelled``,
"pre-empted by a new goal"), as :meth:`GotoSource.cancel` does with its own reason.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Literal

from omnibot.mapping import OccupancyGrid, check_goal, check_start, inflate
from omnibot.motion import Pose2D, Twist
from omnibot.navigation.brake import BrakeSource
from omnibot.navigation.goal import GotoOptions, GotoResult, Outcome, PoseProvider, ScanSource, within
from omnibot.navigation.leg import Leg, judge_leg, leg_heading, obstacle_met, plan_leg, strayed
from omnibot.navigation.runner import WATCHDOG
from omnibot.robot import RobotDescription
from omnibot.runtime import Cycle, Proposal, must_end

GOTO_PRIORITY = 20
"""goto's priority: above the ``path`` follower (10), below scripts (50), ROS 2's cmd_vel (90) and
every person."""
POSE_WAIT = 5.0
"""s a goal waits for a first pose (the localiser's first scan) before it fails."""

State = Literal["idle", "waiting", "planning", "leg", "settling", "standby"]


class GotoSource:
    """Goes to the goal :meth:`go` gives, as a source of a runtime (see the module docstring).

    ``grid`` is the map, ``pose`` the robot's pose in it now (None: not known yet), ``scan`` the
    latest scan's map-frame points for the obstacle watch, ``period`` the runtime's cycle;
    ``on_result`` is called with each goal's result, in the runtime's thread."""

    def __init__(
        self,
        robot: RobotDescription,
        grid: OccupancyGrid,
        period: float,
        pose: PoseProvider,
        *,
        options: GotoOptions | None = None,
        scan: ScanSource | None = None,
        on_result: Callable[[GotoResult], object] = lambda result: None,
        name: str = "goto",
        priority: int = GOTO_PRIORITY,
    ) -> None:
        self.name = name
        self.priority = priority
        self.timeout = max(2.0 * period, 0.05)
        self.wait_reply = False
        self.robot = robot
        self.grid = grid
        self.period = period
        self.pose = pose
        self.scan = scan
        self.options = options or GotoOptions()
        self.on_result = on_result
        self.radius = robot.footprint.bounding_radius
        opts = self.options
        self._cmap = inflate(
            grid, robot_radius=self.radius, margin=opts.margin, allow_unknown=opts.allow_unknown
        )
        self.state: State = "idle"
        self.result: GotoResult | None = None
        """The goal being gone to, or the last one's result once over."""
        self.results: list[GotoResult] = []
        """Every goal's result, in order."""
        self._leg: Leg | None = None
        self._brake: BrakeSource | None = None  # bringing the robot to rest before settling
        self._corrections = 0
        self._replan = False  # settling before a plan (an obstacle, a new goal), not a verdict
        self._t0 = math.nan
        self._now = math.nan  # the latest cycle's link time
        self._since = math.nan  # when the current state began (link time)
        self._deadline = math.inf
        self._leg_end = math.inf
        self._stop_once = False

    # ------------------------------------------------------------------ what the front end calls

    @property
    def active(self) -> bool:
        """A goal is being gone to."""
        return self.state != "idle"

    @property
    def watchdog(self) -> float:
        """The VEL timeout: the leg's follower's, else the follower's at 100 Hz."""
        return self._leg.source.watchdog if self._leg is not None else WATCHDOG

    @property
    def accel(self) -> float:
        """The leg's planned acceleration, or the brake's (0 with neither)."""
        driving = self._leg.source if self._leg is not None else self._brake
        return driving.accel if driving is not None else 0.0

    @property
    def body_accel(self) -> tuple[float, float, float] | None:
        """The leg's planned body acceleration, or the brake's (None with neither)."""
        driving = self._leg.source if self._leg is not None else self._brake
        return driving.body_accel if driving is not None else None

    def check(self, goal: Pose2D) -> None:
        """Raise OffMapError or BlockedError when the robot cannot stand at ``goal`` on the map."""
        check_goal(self._cmap, goal)

    def check_pose(self, pose: Pose2D) -> None:
        """Raise OffMapError, BlockedError or NoPathError when the robot cannot stand at ``pose`` on the
        map (off it, overlapping a wall) or could not leave it (what a plan checks of its start)."""
        check_start(self._cmap, pose)

    def go(self, goal: Pose2D) -> bool:
        """Go to ``goal`` (map frame) from the next cycle on; a goal being gone to is pre-empted
        (True: one was). A goal the robot cannot stand at raises (nothing changes)."""
        self.check(goal)
        moving = self.state in ("leg", "settling")
        leg, brake = self._leg, self._brake
        replaced = self.cancel("pre-empted by a new goal")
        self.result = GotoResult(goal, "stopped", grid=self.grid)
        self._corrections = 0
        self._t0 = math.nan
        self._stop_once = False
        self._enter("waiting")
        if moving:  # stop first, then plan from where the robot stands
            self._enter("settling", self._now)
            self._brake = brake if leg is None else self._brake_from(leg)
            self._replan = True
        return replaced

    def cancel(self, why: str) -> bool:
        """End the goal being gone to (its result ``cancelled``, ``why``); False when there was none."""
        if not self.active:
            return False
        self._finish("cancelled", why)
        return True

    # ------------------------------------------------------------------ the runtime's side

    def propose(self, cycle: Cycle) -> Proposal | None:
        """This cycle's twist for the goal (None when idle)."""
        if self.state == "idle":
            if self._stop_once:  # the cycle after an end mid-way: one zero twist, then silence
                self._stop_once = False
                return Proposal(Twist())
            return None
        t = self._now = cycle.t
        if math.isnan(self._t0):
            self._t0 = t
            if math.isnan(self._since):
                self._since = t
            timeout = self.options.timeout
            self._deadline = math.inf if timeout is None else t + timeout
        why = must_end(cycle, self.name)
        if why:
            self._finish("stalled" if why.startswith("stalled") else "stopped", why)
            return None
        if t > self._deadline:
            self._finish("timed out", f"timed out: not there {t - self._t0:.1f} s after the goal came")
            return None
        previous = cycle.decision
        if self.state not in ("waiting", "standby") and (
            previous.source not in ("", self.name) or previous.lock
        ):
            self._leg = self._brake = None  # someone else has the robot: plan again when it is back
            self._enter("standby", t)
            return Proposal(Twist())
        if self.state == "standby":
            if previous.source not in ("", self.name) or previous.lock:
                return Proposal(Twist())
            self._enter("planning", t)
        if self.state == "waiting":
            if self.pose() is None:
                if t - self._since > POSE_WAIT:
                    self._finish("stopped", f"no pose of the robot in the map after {POSE_WAIT:.0f} s")
                return None
            self._enter("planning", t)
        if self.state == "planning" and not self._plan(cycle):
            return None
        if self.state == "leg":
            return self._follow(cycle)
        return self._settle(cycle)

    def _plan(self, cycle: Cycle) -> bool:
        result = self.result
        here = self.pose()
        estimate = cycle.estimate
        assert result is not None
        if here is None or estimate is None:  # the pose lost (a localiser that stopped): wait again
            self._enter("waiting", cycle.t)
            return False
        result.final = here
        if not result.plans and within(here, result.goal, self.options):
            self._finish("arrived", "")
            return False
        planned = plan_leg(result, here, self.radius, self.options)
        if planned is None:
            self._finish(result.outcome, result.reason)
            return False
        heading = leg_heading(self.robot, self.options, self.scan)
        self._leg = Leg(
            self.robot,
            *planned,
            here,
            estimate.pose,
            self.period,
            heading,
            self.options,
            self.pose,
            self.scan,
            name=self.name,
            priority=self.priority,
        )
        self._leg_end = cycle.t + (self._leg.budget if self.options.timeout is None else math.inf)
        self._enter("leg", cycle.t)
        return True

    def _follow(self, cycle: Cycle) -> Proposal | None:
        leg = self._leg
        result = self.result
        assert leg is not None and result is not None
        leg.watch(cycle)
        proposal = leg.source.propose(cycle)
        source = leg.source
        if leg.watch.points is not None:
            self._leg = None
            if obstacle_met(result, leg.watch.points, leg.why, self.options):
                self._finish(result.outcome, result.reason)
                return None
            self._enter("settling", cycle.t)  # stop, then plan round it
            self._brake = self._brake_from(leg)
            self._replan = True
            return self._settle(cycle)
        if leg.off_path:
            self._leg = None
            if strayed(result, source.failure, self.options):
                self._finish(result.outcome, result.reason)
                return None
            self._enter("settling", cycle.t)  # stop, then plan from where the robot is
            self._brake = self._brake_from(leg)
            self._replan = True
            return self._settle(cycle)
        if source.finished and source.failure:
            self._leg = None
            outcome: Outcome = "stalled" if source.failure.startswith("stalled") else "stopped"
            self._finish(outcome, source.failure)
            return None
        if source.finished:
            self._leg = None
            self._enter("settling", cycle.t)
            self._brake = self._brake_from(leg)
            return self._settle(cycle)
        if cycle.t > self._leg_end:
            self._leg = None
            self._finish(
                "timed out", f"timed out: the leg was not done {cycle.t - self._since:.1f} s after it began"
            )
            return None
        return proposal

    def _brake_from(self, leg: Leg) -> BrakeSource:
        """The brake that brings the robot to rest from ``leg``'s last twist."""
        source = leg.source
        return BrakeSource(
            self.robot, source.twist or Twist(), self.period, name=self.name, watchdog=source.watchdog
        )

    def _settle(self, cycle: Cycle) -> Proposal | None:
        if self._brake is not None:  # to rest first; the settle's time counts from there
            proposal = self._brake.propose(cycle)
            if not self._brake.finished:
                return proposal
            self._brake = None
            self._since = cycle.t
        if cycle.t - self._since < self.options.settle:
            return Proposal(Twist())
        result = self.result
        here = self.pose()
        assert result is not None
        if here is None:
            return Proposal(Twist())
        result.final = here
        if self._replan:
            self._enter("planning", cycle.t)
        elif judge_leg(result, self.options, self._corrections):
            self._finish(result.outcome, result.reason)
            return None
        else:
            self._corrections += 1
            self._enter("planning", cycle.t)
        return Proposal(Twist())

    # ------------------------------------------------------------------ helpers

    def _enter(self, state: State, t: float = math.nan) -> None:
        self.state = state
        self._replan = False
        self._since = t

    def _finish(self, outcome: Outcome, reason: str) -> None:
        result = self.result
        assert result is not None
        mid_way = self.state in ("leg", "standby", "settling")
        self._leg = None
        self._brake = None
        self.state = "idle"
        self._stop_once = mid_way and outcome != "arrived"
        result.outcome = outcome
        result.reason = reason
        final = self.pose()
        if final is not None:
            result.final = final
        if not math.isnan(self._t0):
            result.duration = max(0.0, self._now - self._t0)
        self.results.append(result)
        self.on_result(result)
