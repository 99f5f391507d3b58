"""ROS 2 on the wire without a ROS install: cyclonedds with ROS 2's conventions, a ``cmd_vel`` source
and publishing sinks of the host runtime (docs/ros2.md).

Other packages take the bridge's options and its attaching to a runtime (``omnibot run`` and
``omnibot map --ros2``), its sinks and the ``cmd_vel`` source from this face::

    from omnibot.ros2 import Ros2Sink, add_bridge_options, attach, check

Each loads on first use, with only the module that defines it (the options, ``attach`` and
``Ros2Sink`` load no cyclonedds; ``MapPublisher`` and ``CmdVelSource`` do).
"""

from typing import TYPE_CHECKING

from omnibot.faces import lazy_names

if TYPE_CHECKING:  # the names __getattr__ gives, for type checkers
    from omnibot.ros2.bridge import Ros2Sink
    from omnibot.ros2.cmd_vel import CmdVelSource
    from omnibot.ros2.command import PERIOD, add_bridge_options, attach, check
    from omnibot.ros2.mapping import MapPublisher

_EXPORTS = {
    "bridge": ("Ros2Sink",),
    "cmd_vel": ("CmdVelSource",),
    "command": ("PERIOD", "add_bridge_options", "attach", "check"),
    "mapping": ("MapPublisher",),
}

__all__ = [
    "PERIOD",
    "CmdVelSource",
    "MapPublisher",
    "Ros2Sink",
    "add_bridge_options",
    "attach",
    "bridge",
    "check",
    "cmd_vel",
    "command",
    "mapping",
]

if not TYPE_CHECKING:  # type checkers take each name from its import above
    __getattr__ = lazy_names(__name__, _EXPORTS)
