"""The host client: typed calls in SI, request/reply matching, events and telemetry (docs/client.md).

::

    from omnibot.client import RobotClient

    with RobotClient.open("sim://omni4") as robot:      # or "/dev/ttyUSB0", "tcp://host:port", ...
        robot.move(0.5, 0.4)                            # 0.5 m at 0.4 m/s, returns the MOVE sent
        robot.wait_idle(timeout=5)
        print(robot.status())

Modules: ``client`` (RobotClient: opening, state, switching protocols, closing), built in layers
over ``core`` (the state they share): ``receiving`` (replies to commands, events to listeners),
``waiting`` (pumping), ``sending`` (commands out, the steps before a text command), ``listening``
(listeners, tracers), ``calls`` (the typed calls); the objects a client owns: ``connection``
(Connection: the link's bytes, failures, reopening), ``replies`` (Replies: which command a reply
answers), ``switch`` (ProtocolSwitch: the protocol a client speaks, switching it) on ``tagging``
(TextTags: text's tags and checks). Also ``pending`` (Pending: a command awaiting its reply),
``commands`` (SI -> checked commands), ``limits``, ``events`` (Event types, listeners,
EventRecorder), ``tracing`` (Tracer: what a recorder hears), ``views`` (Hello, Status),
``session`` (robot_session: the robot on the link, the controller left as found), ``wire`` (text
and binary wire formats), ``errors`` (ControllerError subclasses per code).
"""

from omnibot.client.client import DEFAULT_TIMEOUT, RobotClient
from omnibot.client.errors import (
    BatteryStopLatched,
    CalibrationRejected,
    CommandRejected,
    ControllerReset,
    EmergencyStopLatched,
    InternalFault,
    NotSupported,
    OutOfRange,
    QueueFull,
    controller_error,
)
from omnibot.client.events import (
    ErrorEvent,
    Event,
    EventRecorder,
    IdleEvent,
    RangeEvent,
    ResetEvent,
    Telemetry,
    Unexpected,
    WarnEvent,
)
from omnibot.client.limits import Limits
from omnibot.client.pending import Pending
from omnibot.client.session import (
    ClientRecording,
    RobotSession,
    guarded,
    leave,
    open_robot,
    robot_on_link,
    robot_session,
)
from omnibot.client.views import STATE_NAMES, Hello, MoveState, Status
from omnibot.errors import ControllerError, LinkError, LinkTimeout

__all__ = [
    "DEFAULT_TIMEOUT",
    "STATE_NAMES",
    "BatteryStopLatched",
    "CalibrationRejected",
    "ClientRecording",
    "CommandRejected",
    "ControllerError",
    "ControllerReset",
    "EmergencyStopLatched",
    "ErrorEvent",
    "Event",
    "EventRecorder",
    "Hello",
    "IdleEvent",
    "InternalFault",
    "Limits",
    "LinkError",
    "LinkTimeout",
    "MoveState",
    "NotSupported",
    "OutOfRange",
    "Pending",
    "QueueFull",
    "RangeEvent",
    "ResetEvent",
    "RobotClient",
    "RobotSession",
    "Status",
    "Telemetry",
    "Unexpected",
    "WarnEvent",
    "client",
    "commands",
    "controller_error",
    "errors",
    "events",
    "guarded",
    "leave",
    "limits",
    "open_robot",
    "robot_on_link",
    "robot_session",
    "session",
    "views",
]
