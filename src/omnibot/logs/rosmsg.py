"""The ROS 2 messages omnibot writes, built from its own types: stamps and headers, twists,
odometry (with a planar base's variances), laser scans, occupancy grids and the map -> odom
transform, a sonar's range and a telemetry sample's IMU.

Each is a plain function of its values (``schemas.new`` objects), serialised by the recorder, the
Foxglove server and the ROS 2 bridge alike.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from omnibot.client import Telemetry
from omnibot.logs import schemas
from omnibot.motion import Pose2D
from omnibot.scan import Scan


def stamp(ns: int) -> Any:
    """A builtin_interfaces/Time for ``ns`` nanoseconds since the epoch."""
    return schemas.new("builtin_interfaces/msg/Time", sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000)


def header(ns: int, frame: str) -> Any:
    """A ``std_msgs/Header`` stamped at ``ns`` in ``frame``."""
    return schemas.new("std_msgs/msg/Header", stamp=stamp(ns), frame_id=frame)


def quaternion(yaw: float) -> Any:
    """A ``geometry_msgs/Quaternion`` of a rotation by ``yaw`` rad about z."""
    return schemas.new("geometry_msgs/msg/Quaternion", x=0.0, y=0.0, z=math.sin(yaw / 2), w=math.cos(yaw / 2))


def vector(x: float = 0.0, y: float = 0.0, z: float = 0.0) -> Any:
    """A ``geometry_msgs/Vector3``."""
    return schemas.new("geometry_msgs/msg/Vector3", x=x, y=y, z=z)


def twist(vx: float, vy: float, w: float) -> Any:
    """A ``geometry_msgs/Twist``: ``vx``, ``vy`` m/s and ``w`` rad/s about z."""
    return schemas.new("geometry_msgs/msg/Twist", linear=vector(vx, vy), angular=vector(z=w))


def laser_scan(scan: Scan, ns: int) -> Any:
    """sensor_msgs/LaserScan of ``scan`` stamped at ``ns`` in its frame, field for field (a clockwise
    scanner's negative ``angle_increment`` as it is; ``angle_max`` the last ray's direction; ranges
    float32 with ``inf`` for no return, REP 117)."""
    n = len(scan)
    intensities: Any = scan.intensities if scan.intensities is not None else []
    return schemas.new(
        "sensor_msgs/msg/LaserScan",
        header=header(ns, scan.frame),
        angle_min=float(scan.angle_min),
        angle_max=float(scan.angle_min + scan.angle_increment * (n - 1)),
        angle_increment=float(scan.angle_increment),
        time_increment=float(scan.time_increment),
        scan_time=float(scan.scan_time),
        range_min=float(scan.range_min),
        range_max=float(scan.range_max),
        ranges=np.asarray(scan.ranges, dtype=np.float32),
        intensities=np.asarray(intensities, dtype=np.float32),
    )


def occupancy_grid(grid: Any, ns: int, frame: str = "map") -> Any:
    """nav_msgs/OccupancyGrid of an :class:`omnibot.mapping.grid.OccupancyGrid` (row 0, the bottom row,
    first; -1 unknown, 0..100 occupancy), stamped at ``ns`` in ``frame``."""
    rows, cols = grid.shape
    origin = grid.origin
    pose = schemas.new(
        "geometry_msgs/msg/Pose",
        position=schemas.new("geometry_msgs/msg/Point", x=float(origin.x), y=float(origin.y), z=0.0),
        orientation=quaternion(float(origin.theta)),
    )
    info = schemas.new(
        "nav_msgs/msg/MapMetaData",
        map_load_time=stamp(ns),
        resolution=float(grid.resolution),
        width=int(cols),
        height=int(rows),
        origin=pose,
    )
    data = np.ascontiguousarray(grid.data, dtype=np.int8).reshape(-1)
    return schemas.new("nav_msgs/msg/OccupancyGrid", header=header(ns, frame), info=info, data=data)


def map_to_odom(pose: Pose2D, ns: int, parent: str = "map", child: str = "odom") -> Any:
    """tf2_msgs/TFMessage with the one transform ``parent`` -> ``child`` (the SLAM's ``map -> odom``:
    the odometry frame's ``pose`` in the map frame)."""
    transform = schemas.new(
        "geometry_msgs/msg/TransformStamped",
        header=header(ns, parent),
        child_frame_id=child,
        transform=schemas.new(
            "geometry_msgs/msg/Transform",
            translation=vector(float(pose.x), float(pose.y)),
            rotation=quaternion(float(pose.theta)),
        ),
    )
    return schemas.new("tf2_msgs/msg/TFMessage", transforms=[transform])


POSE_VARIANCE = (1e-3, 1e-3, 1e6, 1e6, 1e6, 4e-3)
"""The estimate's pose variances (x, y, z, roll, pitch, yaw): a planar base's, large for what it
cannot observe (robot_localization's convention)."""
TWIST_VARIANCE = (1e-3, 1e-3, 1e6, 1e6, 1e6, 2e-3)


def covariance(variances: Sequence[float] | None) -> Any:
    """A 6x6 row-major covariance with ``variances`` on its diagonal (None: all zero, unknown)."""
    if variances is None:
        return np.zeros(36, dtype=np.float64)
    return np.diag(np.array(variances, dtype=np.float64)).reshape(36)


def odometry(
    ns: int,
    frame: str,
    child: str,
    pose: Pose2D,
    body: tuple[float, float, float],
    variances: tuple[Sequence[float], Sequence[float]] | None = None,
) -> Any:
    """nav_msgs/Odometry: ``pose`` in ``frame``, ``body`` twist (vx, vy, w) in ``child``; ``variances``
    (the pose's, the twist's) on the covariances' diagonals (None: zero)."""
    pose_var, twist_var = variances or (None, None)
    position = schemas.new("geometry_msgs/msg/Point", x=pose.x, y=pose.y, z=0.0)
    return schemas.new(
        "nav_msgs/msg/Odometry",
        header=header(ns, frame),
        child_frame_id=child,
        pose=schemas.new(
            "geometry_msgs/msg/PoseWithCovariance",
            pose=schemas.new("geometry_msgs/msg/Pose", position=position, orientation=quaternion(pose.theta)),
            covariance=covariance(pose_var),
        ),
        twist=schemas.new(
            "geometry_msgs/msg/TwistWithCovariance", twist=twist(*body), covariance=covariance(twist_var)
        ),
    )


def sonar_range(ns: int, sonar: Any, distance: float | None) -> Any:
    """sensor_msgs/Range of ``sonar`` (its description) at ``distance`` m (None: no echo)."""
    return schemas.new(
        "sensor_msgs/msg/Range",
        header=header(ns, f"sonar_{sonar.name}"),
        radiation_type=0,  # ULTRASOUND
        field_of_view=math.radians(sonar.cone_deg),
        min_range=float(sonar.min_range),
        max_range=float(sonar.max_range),
        range=math.inf if distance is None else float(distance),  # REP 117: no echo is +inf
        variance=float(sonar.noise_std) ** 2,
    )


def imu(ns: int, tel: Telemetry) -> Any:
    """sensor_msgs/Imu of a TEL sample: the gyro's rate, the heading as orientation (its covariance
    -1 without one), no linear acceleration (REP 145)."""
    unknown = np.zeros(9, dtype=np.float64)
    unknown[0] = -1.0  # REP 145: no linear acceleration measured
    orientation_cov = np.zeros(9, dtype=np.float64)
    if tel.heading is None:
        orientation_cov[0] = -1.0
    return schemas.new(
        "sensor_msgs/msg/Imu",
        header=header(ns, "imu_link"),
        orientation=quaternion(tel.heading or 0.0),
        orientation_covariance=orientation_cov,
        angular_velocity=vector(z=tel.gyro_rate or 0.0),
        angular_velocity_covariance=np.zeros(9, dtype=np.float64),
        linear_acceleration=vector(),
        linear_acceleration_covariance=unknown,
    )
