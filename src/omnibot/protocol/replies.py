"""The controller's replies, controller -> host: OK, ERROR, HELLO (and how to tell a HELLO frame from
before the window), STATUS; each a frozen dataclass (see :mod:`omnibot.protocol.messages`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import ClassVar, Self

from omnibot.errors import ProtocolError
from omnibot.protocol import codes
from omnibot.protocol.msgbase import Coded, MessageBase, NoParams, check_count


@dataclass(frozen=True)
class Ok(NoParams):
    """``OK``: the command was accepted."""

    TYPE: ClassVar[int] = codes.OK


@dataclass(frozen=True)
class ErrorReply(Coded):
    """``ERROR,<code>,<text>``: a rejected command, or (as an event) a fault of the motion logic."""

    TYPE: ClassVar[int] = codes.ERROR


@dataclass(frozen=True)
class HelloReply(MessageBase):
    """``HELLO,<version>,<robot name>,<motors>``: the answer to HELLO, also sent after a reset.

    ``window`` is the binary frame's: the send window the controller takes (codes.WINDOW_MIN ..
    codes.WINDOW_LIMIT). The text line has none (0)."""

    version: int
    name: str
    motors: int
    window: int = 0
    TYPE: ClassVar[int] = codes.HELLO_REPLY

    def params(self) -> tuple[int, ...]:
        """Version, motor count and window (the binary order; the text line is version, name, motors)."""
        return (self.version, self.motors, self.window)

    def label(self) -> str:
        """The robot's name."""
        return self.name

    @classmethod
    def from_params(cls, params: Sequence[int], label: str = "") -> Self:
        """Build one from version, motor count and window plus the name as ``label`` (the binary
        frame); ProtocolError unless three integers and a window the protocol allows (with
        :data:`HELLO_WITHOUT_WINDOW` when the window reads as a name's letter: a frame from before it)."""
        check_count(cls, params, 3)
        window = params[2]
        if not codes.WINDOW_MIN <= window <= codes.WINDOW_LIMIT:
            if _name_letter(window) and label.isascii() and label.isprintable():
                raise ProtocolError(HELLO_WITHOUT_WINDOW)
            raise ProtocolError(
                f"HELLO reply: window {window} outside {codes.WINDOW_MIN}..{codes.WINDOW_LIMIT}"
            )
        return cls(params[0], label, params[1], window)


HELLO_WITHOUT_WINDOW = (
    "the controller's binary HELLO has no window field: its firmware predates this host; "
    "flash the current firmware"
)
"""Why a HELLO reply frame from before the window (version, motors, name) is refused."""


def _zigzag(value: int) -> int:
    """The zigzag code of ``value``: the byte it was read from when that byte ends a varint."""
    return 2 * value if value >= 0 else -2 * value - 1


def _name_letter(value: int) -> bool:
    """True if ``value`` is what a printable ASCII byte reads as in the window's place: a HELLO
    reply frame from before the window has its name's first letter there."""
    return 0x21 <= _zigzag(value) <= 0x7E


def predates_window(reply: HelloReply, name: str) -> bool:
    """True if ``reply`` was read from a HELLO reply frame from before the window, sent by the
    controller whose text HELLO said ``name``: its window is that name's first letter and its name
    the rest. (A letter that reads as a window the protocol allows, as ``b`` = 49 does, passes
    :meth:`HelloReply.from_params`; the name the controller gave in text tells it apart.)"""
    return len(name) > 1 and reply.name == name[1:] and _zigzag(reply.window) == ord(name[0])


@dataclass(frozen=True)
class StatusReply(MessageBase):
    """``STATUS,<state>,<queued>,<capacity>,<mode>;POWER,<p1>,...,<pn>;MOVE,<L>,<V>,<D>,<C>``."""

    state: int
    queued: int
    capacity: int
    mode: int
    powers: tuple[int, ...]
    move: tuple[int, int, int, int]
    TYPE: ClassVar[int] = codes.STATUS_REPLY

    def __post_init__(self) -> None:
        object.__setattr__(self, "powers", tuple(self.powers))
        object.__setattr__(self, "move", tuple(self.move))
        if len(self.move) != 4:
            raise ProtocolError(f"StatusReply.move needs L,V,D,C, got {self.move}")

    def params(self) -> tuple[int, ...]:
        """State, queued, capacity, mode, the powers, then the remembered MOVE's L, V, D, C."""
        return (self.state, self.queued, self.capacity, self.mode, *self.powers, *self.move)

    @classmethod
    def from_params(cls, params: Sequence[int], label: str = "") -> Self:
        """Build one from 8 to 40 integers (the powers are those between mode and the last four);
        ProtocolError otherwise."""
        check_count(cls, params, 8, 8 + 32)
        p = tuple(params)
        move = (p[-4], p[-3], p[-2], p[-1])
        return cls(p[0], p[1], p[2], p[3], p[4:-4], move)
