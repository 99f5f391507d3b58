"""Nav2's ``navigate_to_pose`` action server without DDS: goals accepted, pre-empted (aborted), refused
(aborted with Nav2's planner codes), cancelled by action_msgs' rules, arrived; results held until the
goal is over; feedback at 5 Hz; the status array; the wire types' layout against ROS 2's.
(tests/ros2/test_rclpy_navigate.py serves it on DDS beside a genuine rclpy.)"""

from __future__ import annotations

import importlib
import math
from typing import Any

import numpy as np
import pytest

pytest.importorskip("cyclonedds", reason="cyclonedds is not installed (pip install 'omnibot[ros2]')")

from omnibot.logs import header, schemas
from omnibot.mapping import PlannedPath
from omnibot.mapping.score import world_grid
from omnibot.motion import Estimate, Pose2D
from omnibot.robot import load_robot
from omnibot.ros2.backend import DEFAULT, Profile
from omnibot.ros2.goal import GOAL_TYPE, GoalPoseSource
from omnibot.ros2.navigate import (
    ABORTED,
    CANCELED,
    EXECUTING,
    SUCCEEDED,
    UNKNOWN,
    NavigateToPose,
    distance_remaining,
)
from omnibot.ros2.types import NAVIGATE, dds_fields, request_type, to_dds
from omnibot.runtime import Cycle
from omnibot.sim import load_world
from tests.ros2.test_path import pose_message

ACTION = "navigate_to_pose/_action/"


class Endpoint:
    """A reader and writer: what is written is taken."""

    def __init__(self) -> None:
        self.samples: list[Any] = []

    def write(self, sample: Any) -> None:
        self.samples.append(sample)

    def take(self, N: int = 1) -> list[Any]:
        taken, self.samples[:N] = self.samples[:N], []
        return taken


class Wire:
    """A dds node's endpoints by name."""

    backend = "dds"

    def __init__(self) -> None:
        self.endpoints: dict[str, Endpoint] = {}

    def reader(self, name: str, typename: str, profile: Profile = DEFAULT) -> Endpoint:
        return self.endpoints.setdefault(name, Endpoint())

    writer = reader

    def service_endpoints(self, name: str, srv: str) -> tuple[Endpoint, Endpoint]:
        return self.reader(name + "Request", srv), self.reader(name + "Reply", srv)


class Bench:
    """The server on a room map, the robot standing at ``here`` (settable)."""

    def __init__(self) -> None:
        self.wire = Wire()
        self.here = Pose2D(1.0, 1.0, 0.0)
        self.said: list[tuple[str, str]] = []
        self.goals = GoalPoseSource(
            self.wire,  # type: ignore[arg-type]
            load_robot("omni4"),
            world_grid(load_world("room")),
            0.02,
            lambda: self.here,
            map_frame="r1/map",
            notify=lambda level, text: self.said.append((level, text)),
        )
        self.server = NavigateToPose(
            self.wire,  # type: ignore[arg-type]
            self.goals,
            stamp=lambda t: round(1e9 * (100.0 + t)),
            notify=lambda level, text: self.said.append((level, text)),
            speed=lambda cycle: 0.25,
        )
        self.t = 0.0
        self.seq = 0

    def cycle(self, seconds: float = 0.02) -> None:
        """Cycles of the runtime for ``seconds``: the source proposes, the server (a sink) runs."""
        end = self.t + seconds
        while self.t < end - 1e-9:
            self.t += 0.02
            cycle = Cycle(0, self.t, self.t, Estimate(self.t, self.here.x, self.here.y, self.here.theta))
            self.goals.propose(cycle)
            self.server(cycle)

    def request(self, service: str, typename: str, **fields: Any) -> None:
        self.seq += 1
        message = schemas.new(typename, **fields)
        sample = request_type(typename)(guid=0xABCD, seq=self.seq, **dds_fields(message, typename))  # type: ignore[call-arg]
        self.wire.endpoints[ACTION + service + "Request"].write(sample)

    def send(self, uuid: int, x: float, y: float, frame: str = "r1/map", tree: str = "") -> None:
        goal = schemas.new(
            f"{NAVIGATE}_Goal",
            pose=schemas.new(GOAL_TYPE, header=header(0, frame), pose=pose_message(x, y, 0.0)),
            behavior_tree=tree,
        )
        self.request("send_goal", f"{NAVIGATE}_SendGoal_Request", goal_id=uuid_msg(uuid), goal=goal)

    def cancel(self, uuid: int, stamp_ns: int = 0) -> None:
        sec, nanosec = divmod(stamp_ns, 1_000_000_000)
        info = schemas.new(
            "action_msgs/msg/GoalInfo",
            goal_id=uuid_msg(uuid),
            stamp=schemas.new("builtin_interfaces/msg/Time", sec=sec, nanosec=nanosec),
        )
        self.request("cancel_goal", "action_msgs/srv/CancelGoal_Request", goal_info=info)

    def ask_result(self, uuid: int) -> None:
        self.request("get_result", f"{NAVIGATE}_GetResult_Request", goal_id=uuid_msg(uuid))

    def replies(self, service: str) -> list[Any]:
        return self.wire.endpoints[ACTION + service + "Reply"].take(N=100)

    def statuses(self) -> dict[int, int]:
        """The last status array: goal (its UUID's first byte) -> status."""
        arrays = self.wire.endpoints[ACTION + "status"].take(N=100)
        assert arrays, "no status published"
        return {s.goal_info.goal_id.uuid[0]: s.status for s in arrays[-1].status_list}


def uuid_msg(n: int) -> Any:
    """A UUID whose first byte is ``n`` (all zero for 0: "no goal" in a cancel request)."""
    return schemas.new(
        "unique_identifier_msgs/msg/UUID", uuid=np.array([n] + [7 if n else 0] * 15, dtype=np.uint8)
    )


@pytest.fixture
def bench() -> Bench:
    return Bench()


def test_goals_are_accepted_and_a_new_one_aborts_the_old(bench: Bench) -> None:
    bench.send(1, 2.5, 1.8)
    bench.cycle()
    ((reply,),) = [bench.replies("send_goal")]
    assert (reply.guid, reply.seq, reply.accepted) == (0xABCD, 1, True)  # the request's header
    assert (reply.stamp.sec, reply.stamp.nanosec) == (100, 20_000_000)
    assert bench.statuses() == {1: EXECUTING}
    assert bench.said[-1] == ("info", "navigate_to_pose received: going to (2.50, 1.80, 0 deg)")
    bench.send(2, 2.0, 2.0)
    bench.ask_result(1)
    bench.ask_result(2)  # held until goal 2 is over
    bench.cycle()
    assert bench.statuses() == {1: ABORTED, 2: EXECUTING}
    ((result,),) = [bench.replies("get_result")]
    assert result.status == ABORTED and result.result.error_code == 0
    assert result.result.error_msg == "pre-empted by a new goal"
    bench.cancel(2)
    bench.cycle()
    ((cancel,),) = [bench.replies("cancel_goal")]
    assert cancel.return_code == 0 and [bytes(g.goal_id.uuid)[0] for g in cancel.goals_canceling] == [2]
    assert bench.statuses() == {1: ABORTED, 2: CANCELED}
    assert not bench.goals.goto.active  # the robot stops
    ((result,),) = [bench.replies("get_result")]
    assert (
        result.status == CANCELED and result.result.error_msg == "cancelled by navigate_to_pose's cancel_goal"
    )
    bench.cancel(2)
    bench.cancel(9)
    bench.ask_result(9)
    bench.cycle()
    assert [c.return_code for c in bench.replies("cancel_goal")] == [3, 2]  # terminated, unknown
    assert [(r.status, r.result.error_code) for r in bench.replies("get_result")] == [(UNKNOWN, 0)]


@pytest.mark.parametrize(
    ("x", "y", "frame", "code", "text"),
    [
        (3.6, 1.2, "r1/map", 206, "navigate_to_pose refused: goal (3.60, 1.20) is inside a wall or obstacle"),
        (30.0, 1.0, "r1/map", 204, "navigate_to_pose refused: goal (30.00, 1.00) is off the map"),
        (2.0, 2.0, "r1/odom", 202, "navigate_to_pose in frame 'r1/odom' refused"),
        (math.nan, 2.0, "r1/map", 200, "navigate_to_pose refused: not a finite position and rotation"),
    ],
)
def test_a_refused_goal_is_accepted_then_aborted_with_nav2s_code(
    bench: Bench, x: float, y: float, frame: str, code: int, text: str
) -> None:
    bench.send(1, 2.5, 1.8)
    bench.cycle()
    bench.send(3, x, y, frame)
    bench.ask_result(3)
    bench.cycle()
    assert bench.replies("send_goal")[-1].accepted is True
    assert bench.statuses() == {1: EXECUTING, 3: ABORTED}  # the goal being gone to goes on
    ((result,),) = [bench.replies("get_result")]
    assert result.status == ABORTED and result.result.error_code == code
    assert result.result.error_msg.startswith(text)
    assert bench.said[-1] == ("warn", result.result.error_msg)  # one warning


def test_an_arrival_succeeds_and_feedback_comes_at_5_hz(bench: Bench) -> None:
    bench.send(4, 2.0, 1.0, tree="navigate_w_replanning.xml")
    bench.cycle(1.0)
    feedback = bench.wire.endpoints[ACTION + "feedback"].take(N=100)
    assert len(feedback) == 5  # 5 Hz
    f = feedback[-1]
    assert bytes(f.goal_id.uuid)[0] == 4 and f.feedback.current_pose.header.frame_id == "r1/map"
    assert (f.feedback.current_pose.pose.position.x, f.feedback.current_pose.pose.position.y) == (1.0, 1.0)
    assert f.feedback.distance_remaining == pytest.approx(1.0, abs=0.06)  # along the plan
    eta = f.feedback.estimated_time_remaining
    assert eta.sec + 1e-9 * eta.nanosec == pytest.approx(f.feedback.distance_remaining / 0.25, rel=1e-6)
    first = feedback[0].feedback.navigation_time
    assert (first.sec, first.nanosec) == (0, 0) and f.feedback.navigation_time.nanosec == 800_000_000
    assert (
        "info",
        "navigate_to_pose: behavior_tree 'navigate_w_replanning.xml' not used (omnibot plans itself)",
    ) in bench.said
    bench.here = Pose2D(2.0, 1.0, 0.0)  # there: the goto judges it arrived
    bench.ask_result(4)
    bench.cycle(2.0)
    assert bench.statuses() == {4: SUCCEEDED}
    ((result,),) = [bench.replies("get_result")]
    assert (result.status, result.result.error_code, result.result.error_msg) == (SUCCEEDED, 0, "")


def test_a_goal_pose_pre_empts_an_action_goal_and_cancel_all(bench: Bench) -> None:
    bench.send(5, 2.5, 1.8)
    bench.cycle()
    bench.wire.endpoints["goal_pose"].write(
        to_dds(
            schemas.new(GOAL_TYPE, header=header(0, "r1/map"), pose=pose_message(2.0, 2.0, 0.0)), GOAL_TYPE
        )
    )
    bench.cycle()
    assert bench.statuses() == {5: ABORTED}
    bench.send(6, 2.5, 1.8)
    bench.cycle()  # goal 6 accepted at 100.06 s
    bench.cancel(0, stamp_ns=100_040_000_000)  # the goals accepted by 100.04 s: none (goal 5 is over)
    bench.cycle()
    ((cancel,),) = [bench.replies("cancel_goal")]
    assert cancel.return_code == 0 and len(cancel.goals_canceling) == 0  # ERROR_NONE, as rcl_action
    bench.cancel(0)  # zero id, zero stamp: every goal
    bench.cycle()
    ((cancel,),) = [bench.replies("cancel_goal")]
    assert cancel.return_code == 0 and len(cancel.goals_canceling) == 1
    assert bench.statuses() == {5: ABORTED, 6: CANCELED}


def test_distance_remaining_is_along_the_plan_from_the_nearest_point_of_it() -> None:
    plan = PlannedPath(
        np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 2.0]]), Pose2D(1.0, 2.0, 0.0), "grid", 0.3, 0.0
    )
    assert distance_remaining(plan, Pose2D(0.8, 0.1, 0.0)) == pytest.approx(2.2)  # from (0.8, 0)
    assert distance_remaining(plan, Pose2D(0.1, 0.0, 0.0)) == pytest.approx(2.9)
    assert distance_remaining(plan, Pose2D(1.2, 1.5, 0.0)) == pytest.approx(0.5)  # from (1, 1.5)
    assert distance_remaining(plan, Pose2D(-1.0, 0.0, 0.0)) == pytest.approx(3.0)  # before its start
    straight = PlannedPath(np.array([[0.0, 0.0], [1.0, 0.0]]), Pose2D(1.0, 0.0, 0.0), "grid", 0.3, 0.0)
    assert distance_remaining(straight, Pose2D(0.7, 0.05, 0.0)) == pytest.approx(0.3)  # no waypoint near
    assert math.isnan(distance_remaining(None, Pose2D(0.0, 0.0, 0.0)))


def test_the_wire_types_are_laid_out_as_ros_2s() -> None:
    """Each request, reply and topic sample, serialized by cyclonedds, against the same values serialized
    by a genuine rclpy (Jazzy's): action_msgs' CancelGoal and GoalStatusArray whole; nav2_msgs has no
    wheel, so its action's parts against rclpy's serialization of their members laid end to end (the
    UUID, the PoseStamped, the string, the Durations...), each where CDR aligns it. A service sample is
    rmw_cyclonedds' 16-byte request header, then the message."""
    rclpy = pytest.importorskip("rclpy.serialization", reason="rclpy is not installed (the test-only extra)")
    from geometry_msgs.msg import PoseStamped

    actions, times = (
        importlib.import_module("action_msgs.msg"),
        importlib.import_module("builtin_interfaces.msg"),
    )
    std, ids = importlib.import_module("std_msgs.msg"), importlib.import_module("unique_identifier_msgs.msg")
    GoalInfo, GoalStatus, GoalStatusArray = actions.GoalInfo, actions.GoalStatus, actions.GoalStatusArray
    CancelGoal = importlib.import_module("action_msgs.srv").CancelGoal
    Duration, UUID = times.Duration, ids.UUID
    Float32, Int16, String = std.Float32, std.Int16, std.String

    def decoded(data: bytes, *parts: Any) -> None:
        """``data`` (CDR without its encapsulation header) cut into ``parts``' lengths as rclpy serializes
        them, each decoded by rclpy equal to its part (rclpy leaves padding bytes as they were in
        memory, so bytes are not compared)."""
        at = 0
        for part in parts:
            size = len(rclpy.serialize_message(part)) - 4
            assert rclpy.deserialize_message(b"\0\x01\0\0" + data[at : at + size], type(part)) == part
            at += size
        assert at == len(data)

    uuid = list(range(1, 17))
    info = GoalInfo(goal_id=UUID(uuid=uuid))
    info.stamp.sec, info.stamp.nanosec = 100, 20_000_000
    pose = PoseStamped()
    pose.header.frame_id = "r1/map"
    pose.header.stamp.sec = 100
    pose.pose.position.x, pose.pose.position.y = 2.5, 1.8
    pose.pose.orientation.z, pose.pose.orientation.w = math.sin(0.25), math.cos(0.25)

    bench = Bench()
    bench.server.goals_kept.clear()
    bench.request(
        "cancel_goal",
        "action_msgs/srv/CancelGoal_Request",
        goal_info=schemas.new(
            "action_msgs/msg/GoalInfo",
            goal_id=schemas.new("unique_identifier_msgs/msg/UUID", uuid=np.array(uuid, dtype=np.uint8)),
            stamp=schemas.new("builtin_interfaces/msg/Time", sec=100, nanosec=20_000_000),
        ),
    )
    (request,) = bench.wire.endpoints[ACTION + "cancel_goalRequest"].take(N=10)
    decoded(bytes(request.serialize())[20:], CancelGoal.Request(goal_info=info))

    goal = schemas.new(
        f"{NAVIGATE}_Goal",
        pose=schemas.new(
            GOAL_TYPE, header=header(100_000_000_000, "r1/map"), pose=pose_message(2.5, 1.8, 0.5)
        ),
        behavior_tree="bt.xml",
    )
    sample = request_type(f"{NAVIGATE}_SendGoal_Request")(  # type: ignore[call-arg]
        guid=1,
        seq=2,
        **dds_fields(
            schemas.new(
                f"{NAVIGATE}_SendGoal_Request",
                goal_id=schemas.new("unique_identifier_msgs/msg/UUID", uuid=np.array(uuid, dtype=np.uint8)),
                goal=goal,
            ),
            f"{NAVIGATE}_SendGoal_Request",
        ),
    )
    data = bytes(sample.serialize())
    assert data[4:20] == (1).to_bytes(8, "little") + (2).to_bytes(8, "little")
    decoded(data[20:], UUID(uuid=uuid), pose, String(data="bt.xml"))

    # the server's own: status, feedback, replies
    bench.here = Pose2D(1.0, 1.0, 0.0)
    bench.send(1, 2.0, 1.0)
    bench.cycle()
    (status,) = bench.wire.endpoints[ACTION + "status"].take(N=10)
    ours = GoalStatusArray(
        status_list=[GoalStatus(goal_info=GoalInfo(goal_id=UUID(uuid=[1] + [7] * 15)), status=2)]
    )
    ours.status_list[0].goal_info.stamp.sec, ours.status_list[0].goal_info.stamp.nanosec = 100, 20_000_000
    decoded(bytes(status.serialize())[4:], ours)
    (feedback,) = bench.wire.endpoints[ACTION + "feedback"].take(N=10)
    f = feedback.feedback
    current = PoseStamped()
    current.header.frame_id = "r1/map"
    current.header.stamp.sec, current.header.stamp.nanosec = 100, 20_000_000
    current.pose.position.x, current.pose.position.y, current.pose.orientation.w = 1.0, 1.0, 1.0
    eta = f.estimated_time_remaining
    decoded(
        bytes(feedback.serialize())[4:],
        UUID(uuid=[1] + [7] * 15),
        current,
        Duration(sec=0, nanosec=0),
        Duration(sec=eta.sec, nanosec=eta.nanosec),
        Int16(data=0),  # rclpy's serialization of it ends with the 2 bytes that align the float32 at 4
        Float32(data=f.distance_remaining),
    )
