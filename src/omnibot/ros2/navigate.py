"""Nav2's ``navigate_to_pose`` action (nav2_msgs/action/NavigateToPose, ROS 2 Jazzy's) on ``omnibot ros2
--map``, served on rmw_cyclonedds' wire.

A ROS 2 action is three services and two topics under ``<name>/_action/`` (rcl_action): ``send_goal``
(``NavigateToPose_SendGoal``: a goal id, a unique_identifier_msgs/UUID, and the goal: a PoseStamped and
a behavior tree's name), ``get_result`` (``NavigateToPose_GetResult``: the goal's terminal status and
its result, answered once the goal is over), ``cancel_goal`` (action_msgs/srv/CancelGoal), ``feedback``
(``NavigateToPose_FeedbackMessage``) and ``status`` (action_msgs/msg/GoalStatusArray, reliable,
transient local, keep-last 1). Services are rmw_cyclonedds' (:mod:`omnibot.ros2.service`): the
companion ``dds`` node's on the rclpy backend (no ``nav2_msgs`` wheel), so a client on
rmw_cyclonedds reaches them; the topics are plain DDS topics any rmw reads.

:class:`NavigateToPose` is a runtime sink beside :class:`~omnibot.ros2.goal.GoalPoseSource`, whose
goto goes to the goals, one at a time, as Nav2's BT navigator does:

* a goal is accepted, then gone to (status EXECUTING) or, when the goal source refuses it (another
  frame than the map's, not finite, off the map, in a wall), aborted at once with Nav2's planner
  error code (:data:`REFUSED`) and the refusal as ``error_msg``; the ``behavior_tree`` is not used
  (omnibot plans and follows itself: said once);
* a new goal (or a ``goal_pose``, an ``initialpose``, an odometry reset) pre-empts the one being gone
  to: it is ABORTED, as Nav2's simple action server aborts the goal a new one replaces;
* feedback every :data:`FEEDBACK_PERIOD` s: the map-frame pose, the time since the goal came, the
  distance along the plan from its point nearest the robot, the time remaining at the current
  speed (0 below 1 cm/s or within 10 cm, as Nav2), the re-plans as recoveries;
* the result when over: SUCCEEDED with ``error_code`` 0 when arrived, else ABORTED with the code of
  :data:`ERROR_CODES` and the reason; a cancel (action_msgs' rules: by id, by stamp, all) stops the
  robot and the goal is CANCELED.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from omnibot.logs import header, quaternion, schemas
from omnibot.mapping import PlannedPath
from omnibot.motion import Pose2D
from omnibot.navigation import GotoResult
from omnibot.ros2.backend import DEFAULT, Profile, RosNode
from omnibot.ros2.goal import GoalPoseSource, Refusal
from omnibot.ros2.service import answer
from omnibot.ros2.types import NAVIGATE, from_dds, register_service_types, to_dds
from omnibot.runtime import Cycle, Level

ACTION = "navigate_to_pose"
CANCEL = "action_msgs/srv/CancelGoal"
STATUS = "action_msgs/msg/GoalStatusArray"
FEEDBACK_PERIOD = 0.2
"""s between two feedback messages (5 Hz)."""
KEPT = 16
"""Goals over whose status and result are kept for ``get_result`` (the newest)."""
STATUS_PROFILE = Profile(depth=1, transient_local=True)
"""rcl_action's status QoS: reliable, transient local, keep-last 1."""

UNKNOWN, ACCEPTED, EXECUTING, CANCELING, SUCCEEDED, CANCELED, ABORTED = range(7)
"""action_msgs/msg/GoalStatus's states."""
ERROR_NONE, ERROR_REJECTED, ERROR_UNKNOWN_GOAL_ID, ERROR_GOAL_TERMINATED = range(4)
"""action_msgs/srv/CancelGoal's return codes."""

ERROR_CODES = {
    "arrived": 0,
    "cancelled": 0,
    "no path": 208,
    "blocked": 208,
    "timed out": 107,
    "stalled": 105,
    "missed": 105,
    "stopped": 100,
    "off path": 106,
}
"""A goal's ``error_code`` by goto's outcome, Nav2 Jazzy's codes (its BT navigator passes on its
planner's and controller's): ComputePathToPose NO_VALID_PATH 208; FollowPath CONTROLLER_TIMED_OUT
107, FAILED_TO_MAKE_PROGRESS 105, NO_VALID_CONTROL 106 (off path: carried off its path again and
again), UNKNOWN 100 (stopped: an emergency stop, a refused command, no pose). Pre-empted or cancelled: 0, as Nav2."""
REFUSED = {"frame": 202, "pose": 200, "off map": 204, "blocked": 206}
"""A refused goal's ``error_code``: ComputePathToPose's TF_ERROR 202 (not in the map frame),
UNKNOWN 200 (not a finite pose), GOAL_OUTSIDE_MAP 204, GOAL_OCCUPIED 206."""


@dataclass
class Goal:
    """One goal of the action: its id (16 bytes), when it was accepted, its state and result."""

    uuid: bytes
    stamp: int
    """ns (the bridge's clock) it was accepted at."""
    t: float
    """The link's time it was accepted at."""
    status: int = EXECUTING
    result: GotoResult | None = None
    error_code: int = 0
    error_msg: str = ""
    waiting: list[Any] = field(default_factory=list)
    """get_result requests answered when it is over."""

    @property
    def over(self) -> bool:
        """In a terminal state."""
        return self.status in (SUCCEEDED, CANCELED, ABORTED)


def uuid_of(message: Any) -> bytes:
    """The 16 bytes of a unique_identifier_msgs/UUID sample."""
    return bytes(int(b) & 0xFF for b in message.uuid)


def distance_remaining(plan: PlannedPath | None, here: Pose2D) -> float:
    """m along ``plan`` from the point of it nearest ``here`` to its end (Nav2's feedback measures from
    the nearest pose of its dense path; a plan here is a polyline of corners, so the robot is projected
    on its nearest segment); NaN without a plan."""
    if plan is None:
        return math.nan
    points = np.asarray(plan.waypoints, dtype=float)
    if len(points) < 2:
        return math.hypot(points[0][0] - here.x, points[0][1] - here.y) if len(points) else math.nan
    a, b = points[:-1], points[1:]
    ab = b - a
    length = np.hypot(ab[:, 0], ab[:, 1])
    p = np.array([here.x, here.y])
    t = np.clip(((p - a) * ab).sum(axis=1) / np.maximum(length**2, 1e-12), 0.0, 1.0)
    nearest = a + t[:, None] * ab
    i = int(np.argmin(np.hypot(*(nearest - p).T)))
    return float((1.0 - t[i]) * length[i] + length[i + 1 :].sum())


def duration(seconds: float) -> Any:
    """A builtin_interfaces/Duration of ``seconds`` (>= 0)."""
    ns = max(0, round(seconds * 1e9))
    return schemas.new("builtin_interfaces/msg/Duration", sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000)


class NavigateToPose:
    """The ``navigate_to_pose`` action server over ``goals`` (see the module docstring): a runtime sink.
    ``stamp`` gives a link time's ns on the bridge's clock; ``speed`` the robot's speed now (m/s)."""

    def __init__(
        self,
        node: RosNode,
        goals: GoalPoseSource,
        *,
        stamp: Callable[[float], int],
        notify: Callable[[Level, str], object],
        speed: Callable[[Cycle], float] = lambda cycle: 0.0,
    ) -> None:
        register_service_types()
        wire: Any = node
        if node.backend == "rclpy":  # the companion dds node's (rclpy is importable here)
            from omnibot.ros2.rclpy_backend import message_class

            why = "" if message_class(NAVIGATE) is None else f"{NAVIGATE} is served on rmw_cyclonedds' wire"
            wire = node.wire(NAVIGATE, why)  # type: ignore[attr-defined]
        self.goals = goals
        self.stamp = stamp
        self.notify = notify
        self.speed = speed
        self.send_goal = wire.service_endpoints(f"{ACTION}/_action/send_goal", f"{NAVIGATE}_SendGoal")
        self.get_result = wire.service_endpoints(f"{ACTION}/_action/get_result", f"{NAVIGATE}_GetResult")
        self.cancel_goal = wire.service_endpoints(f"{ACTION}/_action/cancel_goal", CANCEL)
        self.feedback = wire.writer(f"{ACTION}/_action/feedback", f"{NAVIGATE}_FeedbackMessage", DEFAULT)
        self.status = wire.writer(f"{ACTION}/_action/status", STATUS, STATUS_PROFILE)
        self.goals_kept: list[Goal] = []
        """The goals, oldest first (at most one not over)."""
        self._canceling: GotoResult | None = None
        self._changed = True
        self._last_feedback = -math.inf
        self._tree_said = False
        goals.listeners.append(self._ended)

    @property
    def current(self) -> Goal | None:
        """The goal being gone to."""
        last = self.goals_kept[-1] if self.goals_kept else None
        return None if last is None or last.over else last

    def find(self, uuid: bytes) -> Goal | None:
        """The kept goal of id ``uuid``."""
        return next((g for g in self.goals_kept if g.uuid == uuid), None)

    def __call__(self, cycle: Cycle) -> None:
        """Goals, cancels and result requests that arrived; feedback; the status when it changed."""
        for request in _data(self.send_goal[0]):
            self._receive(request, cycle)
        for request in _data(self.cancel_goal[0]):
            self._cancel(request)
        for request in _data(self.get_result[0]):
            goal = self.find(uuid_of(request.goal_id))
            if goal is None:
                self._answer_result(request, None)
            else:
                goal.waiting.append(request)
        for goal in self.goals_kept:
            if goal.over:
                while goal.waiting:
                    self._answer_result(goal.waiting.pop(0), goal)
        current = self.current
        if current is not None and cycle.t - self._last_feedback >= FEEDBACK_PERIOD - 1e-6:
            self._last_feedback = cycle.t
            self._feedback(current, cycle)
        if self._changed:
            self._changed = False
            self._publish_status()

    # ------------------------------------------------------------------ requests

    def _receive(self, request: Any, cycle: Cycle) -> None:
        message = from_dds(request.goal, f"{NAVIGATE}_Goal")
        goal = Goal(uuid_of(request.goal_id), self.stamp(cycle.t), cycle.t)
        if message.behavior_tree and not self._tree_said:
            self._tree_said = True
            self.notify(
                "info", f"{ACTION}: behavior_tree {message.behavior_tree!r} not used (omnibot plans itself)"
            )
        # the goal is accepted before it is gone to: a pre-empted one is aborted in between
        self.goals_kept.append(goal)
        del self.goals_kept[: max(0, len(self.goals_kept) - KEPT)]
        taken = self.goals.receive(message.pose, ACTION)
        if isinstance(taken, Refusal):
            self._end(goal, ABORTED, REFUSED[taken.kind], taken.text)
        else:
            goal.result = taken
        sec, nanosec = divmod(goal.stamp, 1_000_000_000)
        stamp = schemas.new("builtin_interfaces/msg/Time", sec=sec, nanosec=nanosec)
        answer(self.send_goal[1], request, f"{NAVIGATE}_SendGoal_Response", accepted=True, stamp=stamp)
        self._changed = True

    def _cancel(self, request: Any) -> None:
        """action_msgs' rules, as rcl_action applies them: an id and a zero stamp cancel that goal
        (ERROR_UNKNOWN_GOAL_ID, ERROR_GOAL_TERMINATED when it cannot); otherwise every goal not over
        that was accepted at or before the stamp (a zero id and zero stamp: every goal) or has the id,
        ERROR_NONE even when there is none."""
        info = request.goal_info
        uuid = uuid_of(info.goal_id)
        before = int(info.stamp.sec) * 1_000_000_000 + int(info.stamp.nanosec)
        canceling: list[Goal] = []
        if any(uuid) and before == 0:
            goal = self.find(uuid)
            code = (
                ERROR_UNKNOWN_GOAL_ID if goal is None else ERROR_GOAL_TERMINATED if goal.over else ERROR_NONE
            )
            canceling = [goal] if goal is not None and code == ERROR_NONE else []
        else:
            code = ERROR_NONE
            limit = before if any(uuid) or before else math.inf
            canceling = [g for g in self.goals_kept if not g.over and (g.stamp <= limit or g.uuid == uuid)]
        infos = [self._info(g) for g in canceling]
        for goal in canceling:
            self._canceling = goal.result
            if goal.result is not None:
                self.goals.cancel(f"cancelled by {ACTION}'s cancel_goal")
            self._end(goal, CANCELED, 0, f"cancelled by {ACTION}'s cancel_goal")
            self._canceling = None
        answer(self.cancel_goal[1], request, f"{CANCEL}_Response", return_code=code, goals_canceling=infos)

    # ------------------------------------------------------------------ goals' ends

    def _ended(self, result: GotoResult) -> None:
        """The goal source's result: the action goal it was, if any, ends with it."""
        if result is self._canceling:
            return  # _cancel ends it as CANCELED
        goal = next((g for g in self.goals_kept if g.result is result and not g.over), None)
        if goal is None:
            return  # a goal_pose's
        if result.arrived:
            self._end(goal, SUCCEEDED, 0, "")
        else:
            self._end(goal, ABORTED, ERROR_CODES.get(result.outcome, 100), result.reason or result.outcome)

    def _end(self, goal: Goal, status: int, code: int, why: str) -> None:
        goal.status, goal.error_code, goal.error_msg = status, code, why
        self._changed = True

    # ------------------------------------------------------------------ what goes out

    def _info(self, goal: Goal) -> Any:
        sec, nanosec = divmod(goal.stamp, 1_000_000_000)
        return schemas.new(
            "action_msgs/msg/GoalInfo",
            goal_id=schemas.new("unique_identifier_msgs/msg/UUID", uuid=_uuid_array(goal.uuid)),
            stamp=schemas.new("builtin_interfaces/msg/Time", sec=sec, nanosec=nanosec),
        )

    def _answer_result(self, request: Any, goal: Goal | None) -> None:
        result = schemas.new(
            f"{NAVIGATE}_Result",
            error_code=0 if goal is None else goal.error_code,
            error_msg="" if goal is None else goal.error_msg,
        )
        status = UNKNOWN if goal is None else goal.status
        answer(self.get_result[1], request, f"{NAVIGATE}_GetResult_Response", status=status, result=result)

    def _publish_status(self) -> None:
        statuses = [
            schemas.new("action_msgs/msg/GoalStatus", goal_info=self._info(g), status=g.status)
            for g in self.goals_kept
        ]
        self.status.write(to_dds(schemas.new(STATUS, status_list=statuses), STATUS))

    def _feedback(self, goal: Goal, cycle: Cycle) -> None:
        goto = self.goals.goto
        here = goto.pose()
        result = goal.result
        if here is None or result is None:
            return
        plan = result.plans[-1] if result.plans else None
        left = distance_remaining(plan, here)
        if math.isnan(left):
            left = math.hypot(result.goal.x - here.x, result.goal.y - here.y)
        speed = abs(self.speed(cycle))
        eta = left / speed if speed > 0.01 and left > 0.1 else 0.0
        ns = self.stamp(cycle.t)
        pose = schemas.new(
            "geometry_msgs/msg/PoseStamped",
            header=header(ns, self.goals.map_frame),
            pose=_pose(here),
        )
        feedback = schemas.new(
            f"{NAVIGATE}_Feedback",
            current_pose=pose,
            navigation_time=duration(cycle.t - goal.t),
            estimated_time_remaining=duration(eta),
            number_of_recoveries=result.replans,
            distance_remaining=left,
        )
        message = schemas.new(
            f"{NAVIGATE}_FeedbackMessage",
            goal_id=schemas.new("unique_identifier_msgs/msg/UUID", uuid=_uuid_array(goal.uuid)),
            feedback=feedback,
        )
        self.feedback.write(to_dds(message, f"{NAVIGATE}_FeedbackMessage"))


def _data(reader: Any) -> list[Any]:
    """The samples with data (not disposes) a request reader took."""
    return [s for s in reader.take(N=16) if hasattr(s, "guid")]


def _uuid_array(uuid: bytes) -> Any:
    return np.frombuffer(uuid, dtype=np.uint8).copy()


def _pose(pose: Pose2D) -> Any:
    return schemas.new(
        "geometry_msgs/msg/Pose",
        position=schemas.new("geometry_msgs/msg/Point", x=pose.x, y=pose.y, z=0.0),
        orientation=quaternion(pose.theta),
    )
