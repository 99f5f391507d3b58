"""``initialpose`` and ``reset_odometry`` on the runtime's estimator, and the service's wire (no DDS:
stand-in readers and writers hand over and keep the DDS samples)."""

from __future__ import annotations

import struct
from typing import Any

import pytest

pytest.importorskip("cyclonedds", reason="cyclonedds is not installed (pip install 'omnibot[ros2]')")

from omnibot.estimation import make_estimator
from omnibot.logs import header, quaternion, schemas
from omnibot.motion import Estimate
from omnibot.robot import load_robot
from omnibot.ros2.odometry import POSE, OdometryReset
from omnibot.ros2.service import TRIGGER, TriggerService
from omnibot.ros2.types import request_type, to_dds
from omnibot.runtime import Cycle


class Endpoint:
    """A DataReader / DataWriter stand-in."""

    def __init__(self) -> None:
        self.samples: list[Any] = []

    def take(self, N: int = 1) -> list[Any]:
        taken, self.samples = self.samples[:N], self.samples[N:]
        return taken

    def write(self, sample: Any) -> None:
        self.samples.append(sample)


class Node:
    """A :class:`omnibot.ros2.dds.Node` stand-in: a reader per topic name (``cmd_vel`` per type:
    ``cmd_vel`` TwistStamped's, ``cmd_vel:Twist``...), the publications discovered to hand over."""

    namespace = ""

    def __init__(self) -> None:
        self.endpoints: dict[str, Endpoint] = {}
        self.discovered = Endpoint()

    def reader(self, name: str, typename: str) -> Endpoint:
        if name == "cmd_vel" and not typename.endswith("TwistStamped"):
            name += ":" + typename.rsplit("/", 1)[-1]
        return self.endpoints.setdefault(name, Endpoint())

    def publications(self) -> Endpoint:
        return self.discovered

    def trigger_service(self, name: str, handler: Any) -> TriggerService:
        return TriggerService(self, name, handler)

    def service_endpoints(self, name: str, srv: str) -> tuple[Endpoint, Endpoint]:
        assert srv == TRIGGER
        return self.endpoints.setdefault(name + "Request", Endpoint()), self.endpoints.setdefault(
            name + "Reply", Endpoint()
        )


class Runtime:
    def __init__(self) -> None:
        self.estimator = make_estimator("fused", load_robot("omni4"))


def pose(x: float, y: float, yaw: float, frame: str) -> Any:
    return schemas.new(
        POSE,
        header=header(0, frame),
        pose=schemas.new(
            "geometry_msgs/msg/PoseWithCovariance",
            pose=schemas.new(
                "geometry_msgs/msg/Pose",
                position=schemas.new("geometry_msgs/msg/Point", x=x, y=y, z=0.0),
                orientation=quaternion(yaw),
            ),
            covariance=[0.25] + [0.0] * 35,
        ),
    )


@pytest.fixture
def bench() -> tuple[OdometryReset, Node, Runtime, list[tuple[str, str]], list[str]]:
    node, runtime = Node(), Runtime()
    said: list[tuple[str, str]] = []
    cancelled: list[str] = []
    reset = OdometryReset(
        node,  # type: ignore[arg-type]
        runtime,
        odom_frame="r1/odom",
        notify=lambda level, text: said.append((level, text)),
        on_reset=cancelled.append,
    )
    return reset, node, runtime, said, cancelled


CYCLE = Cycle(0, 0.0, 0.0, None)


def test_initialpose_puts_the_estimate_there(bench: Any) -> None:
    reset, node, runtime, said, cancelled = bench
    node.endpoints["initialpose"].samples.append(to_dds(pose(1.5, -0.5, 2.0, "r1/odom"), POSE))
    reset(CYCLE)
    e: Estimate = runtime.estimator.estimate
    assert (e.x, e.y, e.theta) == pytest.approx((1.5, -0.5, 2.0))
    assert said == [("info", "odometry set by initialpose: x 1.500 m, y -0.500 m, yaw 114.6 deg")]
    assert cancelled == ["odometry set by initialpose"]  # a path in the old frame is cancelled
    node.endpoints["initialpose"].samples.append(to_dds(pose(9.0, 9.0, 0.0, "map"), POSE))
    reset(CYCLE)
    assert runtime.estimator.estimate.x == pytest.approx(1.5)
    assert said[-1][0] == "warn" and "frame 'map' ignored" in said[-1][1]
    assert reset.status().level == 1 and reset.resets == 1


def test_the_reset_service_answers_on_rmw_cyclonedds_wire(bench: Any) -> None:
    reset, node, runtime, _, _ = bench
    runtime.estimator.reset(_pose(1.0, 2.0, 3.0))
    request = request_type(TRIGGER + "_Request")
    node.endpoints["reset_odometryRequest"].samples.append(
        request(guid=0x1122334455667788, seq=7, structure_needs_at_least_one_member=0)  # type: ignore[call-arg]
    )
    reset(CYCLE)
    (reply,) = node.endpoints["reset_odometryReply"].samples
    assert (reply.guid, reply.seq) == (0x1122334455667788, 7)  # the request's header, unchanged
    e = runtime.estimator.estimate
    assert (e.x, e.y, e.theta) == (0.0, 0.0, 0.0)
    # the bytes: rmw_cyclonedds' header (uint64 guid, int64 seq), then std_srvs/Trigger_Response as
    # rosbags decodes it (independent of cyclonedds' encoder)
    data = reply.serialize()
    assert data[:4] == b"\x00\x01\x00\x00"  # CDR little endian
    assert struct.unpack_from("<Qq", data, 4) == (0x1122334455667788, 7)
    body = schemas.deserialize(data[:4] + data[20:], TRIGGER + "_Response")
    assert body.success is True and body.message.startswith("odometry reset by reset_odometry: x 0.000 m")


def _pose(x: float, y: float, theta: float) -> Any:
    from omnibot.motion import Pose2D

    return Pose2D(x, y, theta)


def test_a_service_whose_estimator_cannot_be_set_says_so() -> None:
    node = Node()
    runtime = Runtime()
    runtime.estimator = object()  # type: ignore[assignment]
    said: list[tuple[str, str]] = []
    reset = OdometryReset(node, runtime, odom_frame="odom", notify=lambda lv, t: said.append((lv, t)))  # type: ignore[arg-type]
    assert reset.reset() == (
        False,
        "reset by reset_odometry refused: the estimator cannot be set (it has no reset)",
    )


def test_the_service_types_hash_as_ros_2_jazzy_does() -> None:
    from omnibot.logs import type_hash
    from omnibot.ros2.types import register_service_types

    register_service_types()
    # share/std_srvs/srv/Trigger.json of ROS 2 Jazzy's std_srvs 5.3.6
    assert (
        type_hash(TRIGGER + "_Request")
        == "RIHS01_d010825374ce8918e72bfd826c82603e60f45419e932ea976f807b74a863a199"
    )
    assert (
        type_hash(TRIGGER + "_Response")
        == "RIHS01_2d946c21e2fc3f1e9ca6986a8191d85fcc70097a8bb7771a053564bc47009cdf"
    )
    assert request_type(TRIGGER + "_Request").__idl_typename__ == "std_srvs::srv::dds_::Trigger_Request_"
