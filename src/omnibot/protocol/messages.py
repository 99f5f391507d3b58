"""Typed messages of the motor-controller protocol: one frozen dataclass per command, reply and event.

Messages carry protocol integers in the protocol's units (cm, cm/s, degrees, degrees/s,
1/(1000 cm), ms, raw power); :mod:`omnibot.protocol.units` converts to and from SI. Both codecs
work from the same two methods of every message:

* ``params()``: its integers in wire order (the text parameters; the binary varints);
* ``label()``: its text field (ERROR/WARN text, robot name), "" for the others;

and rebuild it with ``Class.from_params(params, label)``, which raises :class:`ProtocolError` when
the count is wrong. ``TYPE`` is the message's id in :mod:`omnibot.protocol.codes` (binary type).

The messages are defined by direction (:mod:`omnibot.protocol.commands`, :mod:`omnibot.protocol.replies`,
:mod:`omnibot.protocol.events`, on :mod:`omnibot.protocol.msgbase`); this module is where every
importer takes them from (``from omnibot.protocol.messages import Move``), with the unions and
tables over them.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TypeGuard

from omnibot.errors import ProtocolError
from omnibot.protocol import codes
from omnibot.protocol.commands import (
    Ack,
    Cal,
    Delta,
    Hello,
    Mode,
    Move,
    Power,
    Rotate,
    Sonar,
    Status,
    Stop,
    Telem,
    Vel,
)
from omnibot.protocol.events import TEL_GROUPS, Idle, Range, Telemetry, Warn
from omnibot.protocol.replies import (
    HELLO_WITHOUT_WINDOW,
    ErrorReply,
    HelloReply,
    Ok,
    StatusReply,
    predates_window,
)

__all__ = [
    "BY_TYPE",
    "COMMAND_BY_KEYWORD",
    "COMMAND_TYPES",
    "HELLO_WITHOUT_WINDOW",
    "MESSAGE_TYPES",
    "TEL_GROUPS",
    "Ack",
    "Cal",
    "Command",
    "Delta",
    "ErrorReply",
    "Event",
    "Hello",
    "HelloReply",
    "Idle",
    "Malformed",
    "Message",
    "Mode",
    "Move",
    "Ok",
    "Power",
    "Range",
    "Reply",
    "Rotate",
    "Sonar",
    "Status",
    "StatusReply",
    "Stop",
    "Telem",
    "Telemetry",
    "Vel",
    "Warn",
    "check_command",
    "is_command",
    "predates_window",
]


@dataclass(frozen=True)
class Malformed:
    """Bytes that are not a valid message; decoders return it instead of raising.

    ``code`` is the ERROR code a controller answers to such a command (22..25, 34), 0 otherwise.
    """

    raw: bytes
    reason: str
    code: int = 0


Command = Move | Rotate | Delta | Stop | Power | Vel | Mode | Sonar | Telem | Status | Hello | Cal
Reply = Ok | ErrorReply | HelloReply | StatusReply
Event = Range | Warn | ErrorReply | Idle | Telemetry
Message = Command | Ack | Reply | Event

COMMAND_TYPES: tuple[type[Command], ...] = (
    Move,
    Rotate,
    Delta,
    Stop,
    Power,
    Vel,
    Mode,
    Sonar,
    Telem,
    Status,
    Hello,
    Cal,
)
MESSAGE_TYPES: tuple[type[Message], ...] = (
    *COMMAND_TYPES,
    Ack,
    Ok,
    ErrorReply,
    HelloReply,
    StatusReply,
    Range,
    Warn,
    Idle,
    Telemetry,
)
BY_TYPE: dict[int, type[Message]] = {cls.TYPE: cls for cls in MESSAGE_TYPES}
BY_TYPE[codes.ERROR_EVENT] = ErrorReply
COMMAND_BY_KEYWORD: dict[str, type[Command]] = {codes.KEYWORDS[c.TYPE]: c for c in COMMAND_TYPES}


def is_command(message: object) -> TypeGuard[Command]:
    """True for the commands a host sends (not Ack, replies, events)."""
    return isinstance(message, COMMAND_TYPES)


def check_command(message: Command) -> tuple[int, ...]:
    """The command's parameters; raises ProtocolError if a controller would reject their form
    (more than 5, VEL 7, or one outside the 16-bit range). Limits of the robot are not checked."""
    params = message.params()
    most = codes.params_max(message.TYPE)
    if len(params) > most:
        raise ProtocolError(f"{message.keyword}: more than {most} parameters")
    for p in params:
        if not codes.INT_MIN <= p <= codes.INT_MAX:
            raise ProtocolError(f"{message.keyword}: parameter {p} outside the 16-bit range")
    return params
