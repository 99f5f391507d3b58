"""Opening a node on the backend :func:`~omnibot.ros2.backend.choose` picked: the one place that knows
both backends' classes (each imports the interface of :mod:`omnibot.ros2.backend`)."""

from __future__ import annotations

from collections.abc import Mapping

from omnibot.errors import ConfigError
from omnibot.ros2.backend import NODE_NAME, RosNode


def open_node(
    backend: str,
    namespace: str = "",
    *,
    name: str = NODE_NAME,
    sim_time: bool = False,
    env: Mapping[str, str] | None = None,
) -> RosNode:
    """A node on ``backend`` (``rclpy`` or ``dds``, as :func:`choose` gives): ``sim_time``, the robot is
    a simulator's (the rclpy node's ``use_sim_time`` follows the bridge's own ``/clock``)."""
    if backend == "rclpy":
        from omnibot.ros2.rclpy_backend import RclpyNode

        return RclpyNode(namespace, name=name, sim_time=sim_time, env=env)
    if backend == "dds":
        from omnibot.ros2.dds import Node

        return Node(namespace, env, name=name)
    raise ConfigError(f"no ROS 2 backend {backend!r} (rclpy or dds)", key="--ros-backend")
