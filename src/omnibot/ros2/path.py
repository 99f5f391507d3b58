"""A nav_msgs/Path on the ``path`` topic, repeated by omnibot's tracker: a source of the runtime.

The topic is ``path``, not ``plan``: Nav2's planner server publishes every global plan it makes on
``plan`` (in ``map``, for rviz2), and a robot that drove off on each of them would fight Nav2's own
controller. ``path`` is a command: each message is a path for the robot to repeat.

* The path is driven by the follower ``omnibot follow`` uses (the tracker, through
  :func:`omnibot.navigation.following.follower_source`) at the follower's priority (10, below ``cmd_vel``:
  teleop or Nav2 take the robot over, and the follower stands by and resumes where the robot is).
* A new path replaces the one being followed; an empty path cancels it.
* The poses must be in the robot's odom frame (``<prefix>odom``) or carry no frame (omnibot has no
  map: a path in ``map`` is refused with a warning). Each pose's yaw is the heading to hold (a holonomic
  base: it may differ from the direction of travel); a pose without a rotation (an all-zero
  quaternion) keeps the heading before it. When the robot is farther than 2 cm from the first pose
  it first drives straight to it; a single pose is a straight run to it.
* A robot carried farther from the path than the follower chases (a push, the estimate corrected:
  :data:`~omnibot.control.followers.base.OFF_PATH`) is not driven back: the path ends ``failed``
  (``off the path: ... cm from it``), the robot is braked to rest from the last twist
  (:class:`~omnibot.navigation.brake.BrakeSource`) and the abort is on the diagnostics.
* Progress and result: a status line (the runtime's notices: received, replaced, cancelled,
  completed, NOT completed and why) and the ``omnibot: path`` diagnostic status (state, poses,
  length, progress along the path, cross-track error). Given the ``runtime``, each path is judged as
  ``omnibot follow`` judges a run (:class:`~omnibot.navigation.judge.FollowJudge`): a path the
  follower reached the end of is ``judging`` until the verdict (:data:`~omnibot.navigation.runner.SETTLE`
  s later), then ``completed`` or ``failed`` against the tolerances, its accuracy in a status line.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np

from omnibot.control import Path
from omnibot.motion import Estimate, Twist
from omnibot.navigation import (
    FOLLOWER_PRIORITY,
    BrakeSource,
    FollowJudge,
    follower_source,
    summary,
    verdict,
)
from omnibot.ros2.backend import RosNode
from omnibot.ros2.diagnostics import Diagnosed
from omnibot.ros2.odometry import yaw_of
from omnibot.ros2.types import from_dds
from omnibot.runtime import APPROACH_GAP, Cycle, FollowerSource, Level, Proposal, Runtime

PATH = "path"
PATH_TYPE = "nav_msgs/msg/Path"


def path_from_message(msg: Any, state: Estimate) -> Path | None:
    """The omnibot path of a nav_msgs/Path, from where the robot is (``state``); None when a position
    is not finite. A pose without a rotation keeps the heading before it (the robot's for the first);
    a straight run from the robot comes first when it is farther than ``APPROACH_GAP`` from the first
    pose, or when there is one pose only."""
    xs, ys, thetas = [], [], []
    heading = state.theta
    for stamped in msg.poses:
        p = stamped.pose
        yaw = yaw_of(p.orientation)
        heading = heading if yaw is None else yaw
        xs.append(p.position.x)
        ys.append(p.position.y)
        thetas.append(heading)
    if not all(math.isfinite(v) for v in (*xs, *ys)):
        return None
    if len(xs) == 1 or math.hypot(xs[0] - state.x, ys[0] - state.y) > APPROACH_GAP:
        xs.insert(0, state.x)
        ys.insert(0, state.y)
        thetas.insert(0, state.theta)
    return Path(np.array(xs), np.array(ys), np.array(thetas))


class PathSource:
    """Follows the newest nav_msgs/Path of the ``path`` topic (see the module docstring)."""

    def __init__(
        self,
        node: RosNode,
        robot: Any,
        period: float,
        *,
        odom_frame: str,
        notify: Callable[[Level, str], object],
        follower: str = "tracker",
        speed: float | None = None,
        name: str = "path",
        priority: int = FOLLOWER_PRIORITY,
        runtime: Runtime | None = None,
        diagnosed: Diagnosed | None = None,
    ) -> None:
        self.name = name
        self.diagnosed = diagnosed or Diagnosed.of(robot.name)
        """Whose ``path`` status it is."""
        self.priority = priority
        self.robot = robot
        self.period = period
        self.odom_frame = odom_frame
        self.notify = notify
        self.follower = follower
        self.speed = speed
        self.timeout = max(2.0 * period, 0.05)
        self.watchdog: float | None = None
        self.wait_reply = False
        self.reader = node.reader(PATH, PATH_TYPE)
        self.runtime = runtime
        """The runtime whose cycles judge each path (None: the follower's own verdict)."""
        self.current: FollowerSource | None = None
        self.judge: FollowJudge | None = None
        self.state = "idle"
        """idle, following, judging (at the end, until the verdict), completed, failed (NOT
        completed) or cancelled."""
        self.detail = "no path received"
        self.received = 0
        """Path messages taken so far."""
        self.progress = 0.0
        """m along the current path."""
        self.cross = 0.0
        """m off the current path (left positive)."""
        self.refused = ""
        """Why the last path was refused ("" once one is taken)."""
        self.brake: BrakeSource | None = None
        """Brings the robot to rest after a path the follower gave up (the robot off it)."""

    def propose(self, cycle: Cycle) -> Proposal | None:
        """The follower's twist for the newest path (None when there is none to follow)."""
        samples = [s for s in self.reader.take(N=16) if hasattr(s, "__idl_typename__")]
        self.received += len(samples)
        if samples:
            self.receive(from_dds(samples[-1], PATH_TYPE), cycle.estimate)
        current = self.current
        if current is None or current.finished:
            return self._braking(cycle)
        proposal = current.propose(cycle)
        state = cycle.estimate
        if state is not None and len(current.path) > 1:
            proj = current.path.project_near(state.x, state.y, self.progress)
            self.progress, self.cross = proj.s, proj.cross
        if current.finished:
            self._ended(current)
            if current.follower.strayed is not None:
                self.brake = BrakeSource(
                    self.robot,
                    current.twist or Twist(),
                    self.period,
                    name=self.name,
                    watchdog=current.watchdog,
                )
                return self._braking(cycle)
        return proposal

    def _braking(self, cycle: Cycle) -> Proposal | None:
        """The brake's twist while it brings the robot to rest, else None."""
        if self.brake is None or self.brake.finished:
            return None
        return self.brake.propose(cycle)

    def cancel(self, why: str) -> None:
        """End the path being followed (if any): ``why`` in the status."""
        if self.current is not None and not self.current.finished:
            self.current.end(why)
            self.state, self.detail = "cancelled", why
            self.notify("info", f"path cancelled: {why}")

    def receive(self, msg: Any, state: Estimate | None) -> bool:
        """Take a nav_msgs/Path: follow it, cancel with an empty one, or refuse it (a warning)."""
        frame = msg.header.frame_id.lstrip("/")
        if frame not in ("", self.odom_frame):
            return self._refuse(
                f"path in frame {frame!r} ignored: only {self.odom_frame!r} is known here (no map)"
            )
        if not msg.poses:
            if self.current is None or self.current.finished:
                self.notify("info", "path: an empty path, nothing to cancel")
            else:
                self.cancel("an empty path")
            return True
        if state is None:
            return self._refuse("path ignored: no estimate of the robot's pose yet")
        path = path_from_message(msg, state)
        if path is None:
            return self._refuse("path ignored: a pose that is not a finite number")
        replaced = self.current is not None and not self.current.finished
        if replaced and self.current is not None:
            self.current.end("replaced by a new path")
        self.current = follower_source(
            self.robot, path, self.period, self.follower, self.speed, name=self.name, priority=self.priority
        )
        self.watchdog = self.current.watchdog
        if self.runtime is not None:
            current = self.current
            self.judge = FollowJudge(
                self.runtime,
                self.robot,
                current,
                speed=self.speed,
                on_verdict=lambda report: self._judged(current, report),
            )
        self.progress, self.cross, self.refused = 0.0, 0.0, ""
        self.brake = None
        self.state = "following"
        self.detail = f"{len(msg.poses)} poses, {path.length:.2f} m"
        self.notify("info", f"path {'replaced' if replaced else 'received'}: following {self.detail}")
        return True

    def _refuse(self, text: str) -> bool:
        self.notify("warn", text)
        self.refused = text
        return False

    def _ended(self, current: FollowerSource) -> None:
        if current.completed and self.judge is not None:
            self.state, self.detail = "judging", f"reached the end of {self.detail}"
        elif current.completed:
            self.state, self.detail = "completed", f"completed {self.detail}"
            self.notify("info", f"path completed ({current.path.length:.2f} m)")
        else:
            self.state, self.detail = "failed", current.failure or "not finished"
            self.notify("warn", f"path NOT completed: {self.detail}")

    def _judged(self, current: FollowerSource, report: dict[str, Any]) -> None:
        """The verdict on ``current`` (a path since replaced or cancelled: its accuracy only)."""
        level: Level = "info" if report["completed"] else "warn"
        self.notify(level, f"path: {summary(report)}")
        if current is not self.current or self.state != "judging":
            return
        self.state = "completed" if report["completed"] else "failed"
        self.detail = verdict(report)
        self.notify(level, f"path {self.detail}")

    def status(self) -> Any:
        """The ``omnibot: path`` diagnostic status."""
        path = self.current.path if self.current is not None else None
        return self.diagnosed.status(
            1 if self.state == "failed" or self.refused else 0,
            "path",
            f"{self.state}: {self.detail}" + (f" ({self.refused})" if self.refused else ""),
            {
                "state": self.state,
                "poses": 0 if path is None else len(path),
                "length": f"{0.0 if path is None else path.length:.3f}",
                "progress": f"{self.progress:.3f}",
                "cross_track": f"{self.cross:.3f}",
                "received": self.received,
                "refused": self.refused or "none",
            },
        )
