"""Our DDS samples, serialized by cyclonedds, decoded by rosbags' CDR decoder: the same values."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest

pytest.importorskip("cyclonedds", reason="cyclonedds is not installed (pip install 'omnibot[ros2]')")

from omnibot.logs import header, quaternion, schemas, vector
from omnibot.logs.rosmsg import odometry, twist
from omnibot.motion import Pose2D
from omnibot.robot import load_robot
from omnibot.ros2.battery import battery_state
from omnibot.ros2.types import dds_name, dds_type, from_dds, to_dds


def _same(a: Any, b: Any) -> None:
    if hasattr(a, "__msgtype__"):
        assert a.__msgtype__ == b.__msgtype__
        for name in a.__dataclass_fields__:
            if name != "__msgtype__":
                _same(getattr(a, name), getattr(b, name))
    elif isinstance(a, np.ndarray):
        np.testing.assert_array_equal(a, np.asarray(b))
    elif isinstance(a, list):
        assert len(a) == len(b)
        for x, y in zip(a, b, strict=True):
            _same(x, y)
    else:
        assert a == b or (math.isnan(a) and math.isnan(b)), (a, b)


def _messages() -> list[tuple[str, Any]]:
    ns = 1_700_000_000_123_456_789
    odom = odometry(ns, "odom", "base_link", Pose2D(1.5, -0.25, 0.7), (0.3, -0.1, 0.4))
    odom.pose.covariance = np.arange(36, dtype=np.float64) * 0.5
    tf = schemas.new(
        "tf2_msgs/msg/TFMessage",
        transforms=[
            schemas.new(
                "geometry_msgs/msg/TransformStamped",
                header=header(ns, "odom"),
                child_frame_id="base_link",
                transform=schemas.new(
                    "geometry_msgs/msg/Transform", translation=vector(1.0, 2.0), rotation=quaternion(0.3)
                ),
            )
        ],
    )
    joints = schemas.new(
        "sensor_msgs/msg/JointState",
        header=header(ns, "base_link"),
        name=["front_joint", "left_joint", "rear_joint"],
        position=np.array([0.1, -2.0, 3.5]),
        velocity=np.array([1.0, 2.0, -3.0]),
        effort=np.array([], dtype=np.float64),
    )
    imu = schemas.new(
        "sensor_msgs/msg/Imu",
        header=header(ns, "imu_link"),
        orientation=quaternion(-1.2),
        orientation_covariance=np.array([0.01, 0, 0, 0, 0.01, 0, 0, 0, -1.0]),
        angular_velocity=vector(z=0.25),
        angular_velocity_covariance=np.zeros(9),
        linear_acceleration=vector(),
        linear_acceleration_covariance=np.array([-1.0, 0, 0, 0, 0, 0, 0, 0, 0]),
    )
    sonar = schemas.new(
        "sensor_msgs/msg/Range",
        header=header(ns, "sonar_front"),
        radiation_type=0,
        field_of_view=0.25,
        min_range=0.03125,  # float32: values it holds exactly
        max_range=4.0,
        range=float("inf"),
        variance=2.0**-16,  # Jazzy's Range (Humble's has no variance)
    )
    status = schemas.new(
        "diagnostic_msgs/msg/DiagnosticStatus",
        level=2,
        name="omnibot: control",
        message="emergency stop",
        hardware_id="omni4",
        values=[schemas.new("diagnostic_msgs/msg/KeyValue", key="source", value="ros2")],
    )
    diagnostics = schemas.new("diagnostic_msgs/msg/DiagnosticArray", header=header(ns, ""), status=[status])
    stamped = schemas.new(
        "geometry_msgs/msg/TwistStamped", header=header(ns, "base_link"), twist=twist(0.2, -0.1, 0.5)
    )
    urdf = schemas.new("std_msgs/msg/String", data="<robot name='omni4'/>")
    battery = battery_state(load_robot("omni4"), 11.75, ns)
    battery.design_capacity = 2.5  # float32: a value it holds exactly (the preset's 2.2 Ah is not)
    point = schemas.new("geometry_msgs/msg/Point", x=0.5, y=-0.25, z=0.0)
    pose = schemas.new("geometry_msgs/msg/Pose", position=point, orientation=quaternion(0.4))
    path = schemas.new(
        "nav_msgs/msg/Path",
        header=header(ns, "r1/odom"),
        poses=[schemas.new("geometry_msgs/msg/PoseStamped", header=header(ns, "r1/odom"), pose=pose)] * 3,
    )
    initial = schemas.new(
        "geometry_msgs/msg/PoseWithCovarianceStamped",
        header=header(ns, "r1/odom"),
        pose=schemas.new(
            "geometry_msgs/msg/PoseWithCovariance", pose=pose, covariance=np.arange(36, dtype=np.float64)
        ),
    )
    scan = schemas.new(
        "sensor_msgs/msg/LaserScan",
        header=header(ns, "laser"),
        angle_min=-3.0,
        angle_max=3.0,
        angle_increment=0.5,
        time_increment=0.0,
        scan_time=0.125,
        range_min=0.125,
        range_max=8.0,
        ranges=np.array([1.5, float("inf"), 0.25], dtype=np.float32),
        intensities=np.array([], dtype=np.float32),
    )
    return [
        ("nav_msgs/msg/Odometry", odom),
        ("tf2_msgs/msg/TFMessage", tf),
        ("sensor_msgs/msg/JointState", joints),
        ("sensor_msgs/msg/Imu", imu),
        ("sensor_msgs/msg/Range", sonar),
        ("diagnostic_msgs/msg/DiagnosticArray", diagnostics),
        ("geometry_msgs/msg/TwistStamped", stamped),
        ("geometry_msgs/msg/Twist", twist(1.0, 0.0, -0.5)),
        ("std_msgs/msg/String", urdf),
        ("sensor_msgs/msg/BatteryState", battery),
        ("nav_msgs/msg/Path", path),
        ("geometry_msgs/msg/PoseWithCovarianceStamped", initial),
        ("sensor_msgs/msg/LaserScan", scan),
    ]


@pytest.mark.parametrize(("typename", "message"), _messages(), ids=[t for t, _ in _messages()])
def test_rosbags_decodes_what_cyclonedds_encodes(typename: str, message: Any) -> None:
    data = to_dds(message, typename).serialize()
    _same(message, schemas.deserialize(data, typename))
    _same(message, from_dds(dds_type(typename).deserialize(data), typename))


@pytest.mark.parametrize(("typename", "message"), _messages(), ids=[t for t, _ in _messages()])
def test_rosbags_encodes_what_cyclonedds_does_byte_for_byte(typename: str, message: Any) -> None:
    """What a writer's ``write_cdr`` sends (rosbags' CDR, padded to 4 bytes) is what its ``write`` of the
    same message would."""
    ours = schemas.serialize(message, typename)
    theirs = to_dds(message, typename).serialize()
    assert ours.ljust((len(ours) + 3) & ~3, b"\0") == theirs.ljust((len(theirs) + 3) & ~3, b"\0")


def test_type_names_follow_rmw() -> None:
    assert dds_name("nav_msgs/msg/Odometry") == "nav_msgs::msg::dds_::Odometry_"
    cls = dds_type("geometry_msgs/msg/TwistStamped")
    assert cls.__idl_typename__ == "geometry_msgs::msg::dds_::TwistStamped_"
    assert cls.__idl_annotations__["extensibility"] == "final"


def test_every_sink_topic_type_is_built() -> None:
    from omnibot.ros2.bridge import Ros2Sink

    for _, typename, _ in Ros2Sink.topics(load_robot("omni4")):
        assert dds_type(typename).__idl_typename__ == dds_name(typename)
