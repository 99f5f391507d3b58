"""ROS 2 on the wire without a ROS install: cyclonedds with ROS 2's conventions, a ``cmd_vel`` source
and publishing sinks of the host runtime (docs/ros2.md).

Other packages take the bridge's settings and its attaching to a runtime (``omnibot ros2``, ``omnibot
run --ros2`` and ``omnibot map --ros2``, :mod:`omnibot.apps.ros2`), its sinks and the ``cmd_vel``
source from this face::

    from omnibot.ros2 import BridgeSettings, RobotSpec, Ros2Sink, attach

Each loads on first use, with only the module that defines it (the settings, ``attach``, the frame
names, the backend's choice and ``Ros2Sink`` load no cyclonedds; ``MapPublisher`` and
``CmdVelSource`` do). The bridge parses no command line: the commands turn their options into a
:class:`BridgeSettings` and a :class:`RobotSpec` per robot.
"""

from typing import TYPE_CHECKING

from omnibot.faces import lazy_names

if TYPE_CHECKING:  # the names __getattr__ gives, for type checkers
    from omnibot.ros2.assembly import PERIOD, BridgeMap, BridgeSettings, RobotSpec, attach, fqn
    from omnibot.ros2.backend import choose, rclpy_importable
    from omnibot.ros2.bridge import Ros2Sink
    from omnibot.ros2.clock import Timeline
    from omnibot.ros2.cmd_vel import CmdVelSource
    from omnibot.ros2.frames import check_namespace, frame_prefix
    from omnibot.ros2.mapping import MapPublisher

_EXPORTS = {
    "assembly": ("PERIOD", "BridgeMap", "BridgeSettings", "RobotSpec", "attach", "fqn"),
    "backend": ("choose", "rclpy_importable"),
    "bridge": ("Ros2Sink",),
    "clock": ("Timeline",),
    "cmd_vel": ("CmdVelSource",),
    "frames": ("check_namespace", "frame_prefix"),
    "mapping": ("MapPublisher",),
}

__all__ = [
    "PERIOD",
    "BridgeMap",
    "BridgeSettings",
    "CmdVelSource",
    "MapPublisher",
    "RobotSpec",
    "Ros2Sink",
    "Timeline",
    "assembly",
    "attach",
    "backend",
    "bridge",
    "check_namespace",
    "choose",
    "clock",
    "cmd_vel",
    "fqn",
    "frame_prefix",
    "frames",
    "mapping",
    "rclpy_importable",
]

if not TYPE_CHECKING:  # type checkers take each name from its import above
    __getattr__ = lazy_names(__name__, _EXPORTS)
