"""Topic names of an omnibot log: the ROS 2 bridge's names for the standard ones (ros2_controllers
and robot_state_publisher conventions), ``/omnibot/...`` for omnibot's own records. All absolute, as
rosbag2 writes them (``/odom``, as a robot without a namespace publishes it); the bridge publishes the
standard ones relative to the robot's namespace (:func:`omnibot.ros2.bridge.ros_topic`). Logs
written before had ``odom``, ``imu``...: :func:`absolute` reads them alike."""

from __future__ import annotations

ODOM = "/odom"
TF = "/tf"
IMU = "/imu"
JOINT_STATES = "/joint_states"
CMD_VEL = "/cmd_vel"
ROBOT_DESCRIPTION = "/robot_description"
CALIBRATION = "/calibration"
LINK = "/omnibot/link"
PROTOCOL = "/omnibot/protocol"
TRUTH = "/omnibot/truth"
ESTIMATE = "/omnibot/estimate"
"""The estimate's pose exactly (geometry_msgs/Pose2D: theta unwrapped, no quaternion rounding)."""
CONTROL = "/omnibot/control"
"""The runtime's arbitration: which source is in control and why, at each change."""
CYCLE = "/omnibot/cycle"
"""Each runtime cycle while a path follower runs: what the sources were handed, what was decided."""
FOLLOWER = "omnibot_follower"
"""MCAP metadata ``omnibot_follower/RUN``: a follower run's follower, options, limits and path."""
TELEOP = "cmd_vel"
"""What Foxglove's Teleop panel publishes on (geometry_msgs/Twist) to drive through the runtime."""
RANGE_PREFIX = "/range/"
SCAN = "/scan"
"""The robot's range scanner: each revolution as sensor_msgs/LaserScan, in the URDF's scanner frame."""
MAP = "/map"
"""The SLAM's map (nav_msgs/OccupancyGrid, transient local on ROS 2), frame ``map``."""
ADOPTED = "omnibot_estimator"
"""MCAP metadata: the estimate is a runtime's from here on (see ``Recorder.adopt``)."""


def absolute(topic: str) -> str:
    """``topic`` with its leading ``/`` (a log's topic as written before topics were absolute)."""
    return topic if topic.startswith("/") else "/" + topic


def range_topic(sonar: str) -> str:
    """The sensor_msgs/Range topic of the sonar named ``sonar`` in the description."""
    return f"{RANGE_PREFIX}{sonar}"


DEFAULT_ESTIMATOR = "fused"
"""The estimator a recording runs for its ``odom`` and ``/omnibot/estimate`` when a command has none."""
