"""Setting and resetting the odometry from ROS 2: ``initialpose`` and the ``reset_odometry`` service.

* ``initialpose`` (geometry_msgs/PoseWithCovarianceStamped, what rviz2's "2D Pose Estimate" tool
  publishes): the runtime's estimator is put at the pose (x, y and the yaw of its quaternion; the
  covariance is not used: the estimator keeps no pose covariance). The pose must be in the robot's
  odom frame (``<prefix>odom``) or carry no frame: omnibot has no map and no transform from another
  frame, so a pose in ``map`` is refused with a warning rather than applied in the wrong frame.
* ``reset_odometry`` (std_srvs/srv/Trigger, the node's: over the user's rmw on the rclpy backend,
  rmw_cyclonedds' wire on the dds one, :mod:`omnibot.ros2.service`): the estimate goes back to
  (0, 0, 0); the reply says so, or why not.

A reset moves the odom frame under a path being followed (a path is in that frame), so it cancels
the path first (``on_reset``). With a map (``omnibot ros2 --map``) ``initialpose`` is the localiser's
instead (:attr:`OdometryReset.placer`: :meth:`omnibot.ros2.goal.GoalPoseSource.initial_pose`), as
AMCL's: a pose in the map frame re-places it, any other is refused. It is a sink of the runtime: requests are taken once per cycle, and the
next cycle's estimate is the new pose.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable
from typing import Any

from omnibot.motion import Pose2D
from omnibot.ros2.backend import RosNode
from omnibot.ros2.diagnostics import Diagnosed
from omnibot.ros2.types import from_dds
from omnibot.runtime import Cycle, Level

log = logging.getLogger("omnibot.ros2")

INITIALPOSE = "initialpose"
RESET_SERVICE = "reset_odometry"
POSE = "geometry_msgs/msg/PoseWithCovarianceStamped"


def yaw_of(q: Any) -> float | None:
    """The rotation about z of a geometry_msgs/Quaternion (None when it is not a rotation: all zero,
    or not finite)."""
    values = (q.x, q.y, q.z, q.w)
    norm = math.sqrt(sum(v * v for v in values))
    if not math.isfinite(norm) or norm < 1e-9:
        return None
    x, y, z, w = (v / norm for v in values)
    return math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))


def pose_of(p: Any) -> Pose2D | None:
    """The planar pose of a geometry_msgs/Pose (None when its position is not finite or its
    orientation not a rotation)."""
    yaw = yaw_of(p.orientation)
    if yaw is None or not (math.isfinite(p.position.x) and math.isfinite(p.position.y)):
        return None
    return Pose2D(float(p.position.x), float(p.position.y), yaw)


class OdometryReset:
    """``initialpose`` and ``reset_odometry`` applied to ``runtime``'s estimator (module docstring)."""

    def __init__(
        self,
        node: RosNode,
        runtime: Any,
        *,
        odom_frame: str,
        notify: Callable[[Level, str], object],
        on_reset: Callable[[str], object] = lambda why: None,
        diagnosed: Diagnosed | None = None,
    ) -> None:
        self.runtime = runtime
        self.odom_frame = odom_frame
        self.notify = notify
        self.on_reset = on_reset
        self.diagnosed = diagnosed or Diagnosed("")
        """Whose ``odometry`` status it is."""
        self.reader = node.reader(INITIALPOSE, POSE)
        self.service = node.trigger_service(RESET_SERVICE, self.reset)
        self.resets = 0
        self.last = "none yet"
        """What the last request did, in words."""
        self.last_level = 0
        self.placer: Callable[[Any], tuple[bool, str]] | None = None
        """With a map: takes ``initialpose`` messages instead (done, what happened)."""

    def set_pose(self, pose: Pose2D, why: str) -> tuple[bool, str]:
        """Put the estimate at ``pose``; (done, what happened)."""
        estimator = self.runtime.estimator
        reset = getattr(estimator, "reset", None)
        if reset is None:
            text = f"{why} refused: the estimator cannot be set (it has no reset)"
            self._report(1, "warn", text)
            return False, text
        self.on_reset(f"odometry {why}")
        reset(pose)
        self.resets += 1
        text = f"odometry {why}: x {pose.x:.3f} m, y {pose.y:.3f} m, yaw {math.degrees(pose.theta):.1f} deg"
        self._report(0, "info", text)
        return True, text

    def reset(self) -> tuple[bool, str]:
        """The service: the estimate back to (0, 0, 0)."""
        return self.set_pose(Pose2D(0.0, 0.0, 0.0), f"reset by {RESET_SERVICE}")

    def _report(self, level: int, notice: Level, text: str) -> None:
        self.last, self.last_level = text, level
        self.notify(notice, text)

    def __call__(self, cycle: Cycle) -> None:
        """Take the poses and reset requests that arrived."""
        samples = [s for s in self.reader.take(N=16) if hasattr(s, "__idl_typename__")]
        if samples:
            self.initial_pose(from_dds(samples[-1], POSE))
        self.service.poll()

    def initial_pose(self, msg: Any) -> bool:
        """Apply an ``initialpose`` message (refused, with a warning, when not in the odom frame or not
        a pose); with :attr:`placer`, the placer's (its outcome reported the same way)."""
        if self.placer is not None:
            done, text = self.placer(msg)
            self._report(0 if done else 1, "info" if done else "warn", text)
            return done
        frame = msg.header.frame_id.lstrip("/")
        if frame not in ("", self.odom_frame):
            self._report(
                1,
                "warn",
                f"initialpose in frame {frame!r} ignored: only {self.odom_frame!r} is known here "
                "(no map; set rviz2's fixed frame to it)",
            )
            return False
        pose = pose_of(msg.pose.pose)
        if pose is None:
            self._report(1, "warn", "initialpose ignored: not a finite position and rotation")
            return False
        done, _ = self.set_pose(pose, f"set by {INITIALPOSE}")
        return done

    def status(self) -> Any:
        """The ``omnibot: odometry`` diagnostic status: resets so far, the last one."""
        return self.diagnosed.status(self.last_level, "odometry", self.last, {"resets": self.resets})
