"""The message types of an omnibot log: ROS 2's own (from rosbags' Jazzy type store) and ours.

Standard topics carry standard ROS 2 messages so that Foxglove and ``ros2 bag`` understand them;
omnibot's own records are the package ``omnibot_msgs``, defined here in ROS 2 ``.msg`` syntax and
registered in the same type store, so one serializer (rosbags' CDR) writes every message::

    /omnibot/link       omnibot_msgs/msg/LinkBytes        raw bytes both ways (TX, RX, ERR, CLOSE)
    /omnibot/protocol   omnibot_msgs/msg/ProtocolLine     each command, reply and event as text
    /omnibot/control    omnibot_msgs/msg/Control          the runtime's arbitration, at each change
    /omnibot/cycle      omnibot_msgs/msg/Cycle            each runtime cycle while a follower runs
    /omnibot/truth      nav_msgs/msg/Odometry             the simulator's ground truth

:func:`typestore` returns the store; :func:`schema_text` the ``ros2msg`` schema (the definition
followed by its dependencies, rosbag2's layout) and :func:`type_hash` the RIHS01 type hash.
"""

from __future__ import annotations

from functools import cache
from typing import Any

from rosbags.typesys import Stores, get_typestore
from rosbags.typesys.msg import get_types_from_msg
from rosbags.typesys.store import Typestore

LINK_BYTES = "omnibot_msgs/msg/LinkBytes"
PROTOCOL_LINE = "omnibot_msgs/msg/ProtocolLine"
CONTROL = "omnibot_msgs/msg/Control"
CYCLE = "omnibot_msgs/msg/Cycle"

OWN_TYPES = {
    LINK_BYTES: (
        "# Bytes that went over the link to the controller, as the spy+ wrapper sees them.\n"
        "builtin_interfaces/Time stamp\n"
        "string kind  # TX (host wrote), RX (host read), ERR (the link failed), CLOSE\n"
        "uint8[] data\n"
        "string note  # the error of an ERR\n"
    ),
    PROTOCOL_LINE: (
        "# One protocol message, decoded, in the text protocol's form (also when sent in binary).\n"
        "builtin_interfaces/Time stamp\n"
        "string direction  # command (host to controller), reply, event\n"
        "string keyword  # MOVE, OK, TEL, ...\n"
        "string text  # the whole message, e.g. MOVE,2,40,0,0\n"
    ),
    CONTROL: (
        "# The runtime's arbitration (twist_mux): which command source is in control and why.\n"
        "builtin_interfaces/Time stamp\n"
        "string source  # the source that drives (pad, page, foxglove, follower...), empty for nobody\n"
        "string reason  # in words, e.g. pad (priority 200) over follower\n"
        "string lock  # the lock that holds the robot (emergency stop, deadman), empty for none\n"
        "bool estop  # that lock is an emergency stop\n"
        "bool latched  # the controller holds a latched emergency stop (sonar)\n"
        "geometry_msgs/Twist twist  # what the source asked for (m/s, rad/s; zero when nothing)\n"
    ),
    CYCLE: (
        "# One cycle of the runtime while a path follower runs: what the command sources were handed\n"
        "# and what was decided (omnibot log replay re-runs the follower on it).\n"
        "builtin_interfaces/Time stamp\n"
        "uint32 run  # the follower run (MCAP metadata omnibot_follower/RUN)\n"
        "uint64 index  # the runtime's cycle number\n"
        "float64 now  # the cycle clock, s\n"
        "float64 t  # the link clock, s\n"
        "bool has_estimate  # false: no estimate yet (the fields below are zero)\n"
        "float64 estimate_t  # the estimate handed to the sources: its time (s), pose, world velocity\n"
        "float64 x\n"
        "float64 y\n"
        "float64 theta\n"
        "float64 vx\n"
        "float64 vy\n"
        "float64 w\n"
        "bool slipping\n"
        "bool standstill\n"
        "string source  # the source in control after this cycle's decision, empty for nobody\n"
        "string lock  # the lock that holds the robot, empty for none\n"
        "bool estop  # that lock is an emergency stop\n"
        "bool latched  # the controller holds a latched emergency stop\n"
        "bool has_twist  # the decision carries a twist (sent with VEL)\n"
        "geometry_msgs/Twist twist  # what the source in control asked for (m/s, rad/s)\n"
        "string[] errors  # error notices for the follower this cycle (a refused command...)\n"
    ),
}


@cache
def typestore() -> Typestore:
    """ROS 2 Jazzy's message types (Kilted's are the same) plus ``omnibot_msgs``.

    Not Humble's: its sensor_msgs/Range lacks ``variance``, so Jazzy's and Kilted's subscribers (rclpy,
    rviz2) would never take our ranges (another type hash, a shorter message)."""
    store = get_typestore(Stores.ROS2_JAZZY)
    for name, text in OWN_TYPES.items():
        store.register(get_types_from_msg(text, name))
    return store


def schema_text(typename: str) -> str:
    """The ``ros2msg`` schema of ``typename``: its definition, then each dependency after a line
    of ``=`` and ``MSG: pkg/Name`` (what rosbag2 and Foxglove read)."""
    text, _ = typestore().generate_msgdef(typename, ros_version=2)
    return text


def type_hash(typename: str) -> str:
    """The RIHS01 type description hash rosbag2 puts in its metadata."""
    return typestore().hash_rihs01(typename)


def new(typename: str, **fields: Any) -> Any:
    """A message object of ``typename``."""
    return typestore().types[typename](**fields)


def serialize(message: Any, typename: str) -> bytes:
    """CDR bytes (little endian, with the encapsulation header) of ``message``."""
    return bytes(typestore().serialize_cdr(message, typename))


def deserialize(data: bytes | memoryview, typename: str) -> Any:
    """A ROS 2 message of ``typename`` from its CDR bytes."""
    return typestore().deserialize_cdr(data, typename)
