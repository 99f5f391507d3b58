"""ROS 2 on the wire without a ROS install: cyclonedds with ROS 2's conventions, a ``cmd_vel`` source
and publishing sinks of the host runtime (docs/ros2.md)."""

__all__ = ["bridge", "command", "mapping"]
