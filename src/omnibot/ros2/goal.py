"""Nav2's ``goal_pose`` on a saved map (``omnibot ros2 --map MAP.yaml``): localise, publish the map
and ``map -> odom``, go to each goal.

* :class:`Localisation` is a runtime sink: a :class:`~omnibot.mapping.session.LocalisingSink` (the
  particle filter and scan-to-map matching of ``omnibot goto``) fed by the runtime's scans and
  odometry, started at the robot's pose in the map; it publishes the map once on ``map``
  (nav_msgs/OccupancyGrid, transient local: a node that joins late gets it) and the localiser's
  ``map -> odom`` on ``/tf`` at 20 Hz once the first scan is placed, through the bridge's
  :class:`~omnibot.ros2.bridge.Ros2Sink`.
* :class:`GoalPoseSource` reads ``goal_pose`` (geometry_msgs/PoseStamped, what rviz2's "2D Goal
  Pose" tool and Nav2's users publish) and goes there with a
  :class:`~omnibot.navigation.goto_source.GotoSource` (plan on the map inflated by the robot's
  radius, the tracker, the scan watching for what the map lacks, re-plans), at priority 20: ``cmd_vel``
  (90) and every person take the robot over, and goto plans again from where they left it. A goal
  must be in the map frame (``<prefix>map``); any other frame, a goal off the map, inside a wall or
  too near one, or not a finite pose is refused with one warning and changes nothing. A new goal
  pre-empts the one being gone to. The outcome (arrived, or why not: no path, blocked, timed out,
  stalled, stopped, missed, cancelled) is a status line and the ``omnibot: goal`` diagnostic status.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

from omnibot.errors import ConfigError
from omnibot.logs.recorder import map_to_odom, occupancy_grid
from omnibot.logs.topics import MAP, TF
from omnibot.mapping.grid import OccupancyGrid
from omnibot.mapping.session import LocalisingSink
from omnibot.motion import Pose2D
from omnibot.navigation.goto import GotoOptions, GotoResult
from omnibot.navigation.goto_source import GotoSource
from omnibot.robot.description import RobotDescription
from omnibot.ros2.backend import LATCHED, RosNode
from omnibot.ros2.bridge import Diagnosed, Ros2Sink
from omnibot.ros2.mapping import MAP_TYPE, TF_PERIOD
from omnibot.ros2.odometry import yaw_of
from omnibot.ros2.types import from_dds
from omnibot.runtime.cycle import Cycle, Level
from omnibot.runtime.sources import Proposal

GOAL_POSE = "goal_pose"
GOAL_TYPE = "geometry_msgs/msg/PoseStamped"


class Localisation:
    """A sink: ``sink`` (a LocalisingSink) fed every cycle; the map and ``map -> odom`` published
    through ``bridge`` (see the module docstring). :meth:`close` when the run ends."""

    def __init__(self, bridge: Ros2Sink, grid: OccupancyGrid, sink: LocalisingSink) -> None:
        self.bridge = bridge
        self.grid = grid
        self.sink = sink
        bridge.add_topic(MAP, MAP_TYPE, LATCHED)
        self._map_sent = False
        self._last_tf = -math.inf

    def pose(self) -> Pose2D | None:
        """The robot's map-frame pose now (None until the first scan placed it)."""
        return self.sink.pose_now() if self.sink.updates else None

    def __call__(self, cycle: Cycle) -> None:
        """Feed the localiser; the map once, ``map -> odom`` every TF_PERIOD s once localised."""
        self.sink(cycle)
        ns = self.bridge.recorder.ns(cycle.t)
        if not self._map_sent:
            self._map_sent = True
            self.bridge.write(MAP, occupancy_grid(self.grid, ns))
        if self.sink.updates and cycle.now - self._last_tf >= TF_PERIOD:
            self._last_tf = cycle.now
            self.bridge.write(TF, map_to_odom(self.sink.map_to_odom_now(), ns))

    def close(self) -> None:
        """Finish the localiser's work and close it."""
        self.sink.close()


class GoalPoseSource:
    """Goes to the newest ``goal_pose`` (see the module docstring): a runtime source."""

    def __init__(
        self,
        node: RosNode,
        robot: RobotDescription,
        grid: OccupancyGrid,
        period: float,
        pose: Callable[[], Pose2D | None],
        *,
        map_frame: str,
        notify: Callable[[Level, str], object],
        scan: Callable[[], Any] | None = None,
        options: GotoOptions | None = None,
        diagnosed: Diagnosed | None = None,
    ) -> None:
        self.map_frame = map_frame
        self.notify = notify
        self.diagnosed = diagnosed or Diagnosed.of(robot.name)
        self.reader = node.reader(GOAL_POSE, GOAL_TYPE)
        self.goto = GotoSource(
            robot, grid, period, pose, options=options, scan=scan, on_result=self._result, name="goal_pose"
        )
        self.name = self.goto.name
        self.priority = self.goto.priority
        self.timeout = self.goto.timeout
        self.wait_reply = False
        self.received = 0
        self.refused = ""
        """Why the last goal was refused ("" once one is taken)."""
        self.detail = "no goal received"

    @property
    def watchdog(self) -> float:
        """The goto's VEL timeout."""
        return self.goto.watchdog

    @property
    def accel(self) -> float:
        """The goto's planned acceleration."""
        return self.goto.accel

    @property
    def body_accel(self) -> tuple[float, float, float] | None:
        """The goto's planned body acceleration."""
        return self.goto.body_accel

    def propose(self, cycle: Cycle) -> Proposal | None:
        """Take the newest goal, if one came; the goto's twist."""
        samples = [s for s in self.reader.take(N=16) if hasattr(s, "__idl_typename__")]
        self.received += len(samples)
        if samples:
            self.receive(from_dds(samples[-1], GOAL_TYPE))
        return self.goto.propose(cycle)

    def cancel(self, why: str) -> None:
        """End the goal being gone to (if any), ``why`` in its result."""
        self.goto.cancel(why)

    def receive(self, msg: Any) -> bool:
        """Go to a geometry_msgs/PoseStamped, or refuse it (one warning)."""
        frame = msg.header.frame_id.lstrip("/")
        if frame != self.map_frame:
            return self._refuse(
                f"goal_pose in frame {frame!r} refused: goals are taken in the map frame {self.map_frame!r}"
            )
        p = msg.pose
        yaw = yaw_of(p.orientation)
        if yaw is None or not (math.isfinite(p.position.x) and math.isfinite(p.position.y)):
            return self._refuse("goal_pose refused: not a finite position and rotation")
        goal = Pose2D(float(p.position.x), float(p.position.y), yaw)
        try:
            replaced = self.goto.go(goal)
        except ConfigError as exc:  # OffMapError, BlockedError: the robot cannot stand there
            return self._refuse(f"goal_pose refused: {exc}")
        self.refused = ""
        self.detail = f"going to ({goal.x:.2f}, {goal.y:.2f}, {math.degrees(goal.theta):.0f} deg)"
        self.notify("info", f"goal_pose {'replaced' if replaced else 'received'}: {self.detail}")
        return True

    def _refuse(self, text: str) -> bool:
        self.refused = text
        self.notify("warn", text)
        return False

    def _result(self, result: GotoResult) -> None:
        self.detail = result.summary()
        level: Level = "info" if result.arrived else "warn"
        self.notify(level, f"goal_pose: {self.detail}")

    def status(self) -> Any:
        """The ``omnibot: goal`` diagnostic status."""
        goto = self.goto
        result = goto.result
        state = goto.state if goto.active else ("idle" if result is None else result.outcome)
        values: dict[str, object] = {
            "state": state,
            "received": self.received,
            "refused": self.refused or "none",
        }
        if result is not None:
            g = result.goal
            values["goal"] = f"{g.x:.3f},{g.y:.3f},{math.degrees(g.theta):.1f}"
            values["outcome"] = "going" if goto.active else result.outcome
            values["reason"] = result.reason or "none"
            values["error_m"] = f"{result.error:.3f}"
            values["heading_error_deg"] = f"{math.degrees(result.heading_error):.1f}"
            values["plans"] = len(result.plans)
            values["replans"] = result.replans
        failed = result is not None and not goto.active and not result.arrived
        text = self.detail + (f" ({self.refused})" if self.refused else "")
        return self.diagnosed.status(1 if failed or self.refused else 0, "goal", text, values)
