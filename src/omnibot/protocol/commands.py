"""The protocol's commands, host -> controller (MOVE, ROTATE, DELTA, STOP, POWER, VEL, MODE, SONAR,
TELEM, STATUS, HELLO, CAL) and ACK; each a frozen dataclass (see :mod:`omnibot.protocol.messages`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import ClassVar, Self

from omnibot.errors import ProtocolError
from omnibot.protocol import codes
from omnibot.protocol.msgbase import MessageBase, NoParams, check_command_count


@dataclass(frozen=True)
class Move(MessageBase):
    """``MOVE,L,V,D,C``: travel L cm at V cm/s on course D degrees, curvature C in 1/(1000 cm)."""

    distance: int
    speed: int
    course: int
    curvature: int
    TYPE: ClassVar[int] = codes.MOVE

    def params(self) -> tuple[int, ...]:
        """L, V, D, C in wire order."""
        return (self.distance, self.speed, self.course, self.curvature)

    @classmethod
    def from_params(cls, params: Sequence[int], label: str = "") -> Self:
        """Build one from its integers in wire order; ProtocolError when their count is wrong."""
        check_command_count(cls, params)
        return cls(*params)


@dataclass(frozen=True)
class Rotate(MessageBase):
    """``ROTATE,A,F``: turn in place by A degrees at F degrees/s."""

    angle: int
    rate: int
    TYPE: ClassVar[int] = codes.ROTATE

    def params(self) -> tuple[int, ...]:
        """A, F in wire order."""
        return (self.angle, self.rate)

    @classmethod
    def from_params(cls, params: Sequence[int], label: str = "") -> Self:
        """Build one from its integers in wire order; ProtocolError when their count is wrong."""
        check_command_count(cls, params)
        return cls(*params)


@dataclass(frozen=True)
class Delta(MessageBase):
    """``DELTA,L,V,D,C,R``: the remembered MOVE plus these increments, max(R,1) times."""

    distance: int
    speed: int
    course: int
    curvature: int
    repeat: int
    TYPE: ClassVar[int] = codes.DELTA

    def params(self) -> tuple[int, ...]:
        """L, V, D, C, R in wire order."""
        return (self.distance, self.speed, self.course, self.curvature, self.repeat)

    @classmethod
    def from_params(cls, params: Sequence[int], label: str = "") -> Self:
        """Build one from its integers in wire order; ProtocolError when their count is wrong."""
        check_command_count(cls, params)
        return cls(*params)


@dataclass(frozen=True)
class Stop(NoParams):
    """``STOP``: motors off, queue cleared, remembered MOVE reset, latched emergency stop released."""

    TYPE: ClassVar[int] = codes.STOP


@dataclass(frozen=True)
class Power(MessageBase):
    """``POWER,T,P1,...,Pn``: raw power Pi on motor i for T ms (n <= 4)."""

    time_ms: int
    powers: tuple[int, ...]
    TYPE: ClassVar[int] = codes.POWER

    def __post_init__(self) -> None:
        object.__setattr__(self, "powers", tuple(self.powers))

    def params(self) -> tuple[int, ...]:
        """T then one power per motor, in wire order."""
        return (self.time_ms, *self.powers)

    @classmethod
    def from_params(cls, params: Sequence[int], label: str = "") -> Self:
        """Build one from T and the motors' powers; ProtocolError when their count is wrong."""
        check_command_count(cls, params)
        return cls(params[0], tuple(params[1:]))


@dataclass(frozen=True)
class Vel(MessageBase):
    """``VEL,VX,VY,W,T[,A]`` or ``VEL,VX,VY,W,T,AX,AY,AW``: hold body velocity (cm/s, cm/s,
    degrees/s) for at most T ms. A (protocol version 3) is the host's planned rate of change of the
    speed, cm/s^2 (0: none, and then it is not sent, so a version 2 controller reads the same
    command). ``body`` (version 4) is the planned acceleration of the body: AX, AY cm/s^2 along the
    body's x and y axes (the centre's acceleration in the world, centripetal included) and AW
    degrees/s^2; None: not sent. A VEL carries one of the two at most."""

    vx: int
    vy: int
    w: int
    time_ms: int
    accel: int = 0
    body: tuple[int, int, int] | None = None
    TYPE: ClassVar[int] = codes.VEL

    def __post_init__(self) -> None:
        if self.accel and self.body is not None:
            raise ValueError("VEL carries version 3's A or version 4's AX, AY, AW, not both")

    def params(self) -> tuple[int, ...]:
        """VX, VY, W, T (then A when it is not 0, or AX, AY, AW when given) in wire order."""
        if self.body is not None:
            return (self.vx, self.vy, self.w, self.time_ms, *self.body)
        if self.accel:
            return (self.vx, self.vy, self.w, self.time_ms, self.accel)
        return (self.vx, self.vy, self.w, self.time_ms)

    @classmethod
    def from_params(cls, params: Sequence[int], label: str = "") -> Self:
        """Build one from its integers in wire order (4, 5 or 7 of them); ProtocolError when their
        count is wrong."""
        check_command_count(cls, params)
        if len(params) == 6:
            raise ProtocolError("Vel takes 4, 5 or 7 integers, got 6")
        vx, vy, w, t = params[:4]
        if len(params) == 7:
            return cls(vx, vy, w, t, body=(params[4], params[5], params[6]))
        return cls(vx, vy, w, t, params[4] if len(params) == 5 else 0)


@dataclass(frozen=True)
class Mode(MessageBase):
    """``MODE,M``: mode bits (codes.MODE_SIMULATION, MODE_CLOSED_LOOP, MODE_BINARY)."""

    mask: int
    TYPE: ClassVar[int] = codes.MODE

    def params(self) -> tuple[int, ...]:
        """The mode mask alone."""
        return (self.mask,)

    @classmethod
    def from_params(cls, params: Sequence[int], label: str = "") -> Self:
        """Build one from its integers in wire order; ProtocolError when their count is wrong."""
        check_command_count(cls, params)
        return cls(*params)


@dataclass(frozen=True)
class Sonar(MessageBase):
    """``SONAR,S,P,LOW,HIGH,STOP``: sonar S measures every P ms; RANGE band; emergency-stop cm."""

    sonar: int
    period_ms: int
    low: int
    high: int
    stop: int
    TYPE: ClassVar[int] = codes.SONAR

    def params(self) -> tuple[int, ...]:
        """S, P, LOW, HIGH, STOP in wire order."""
        return (self.sonar, self.period_ms, self.low, self.high, self.stop)

    @classmethod
    def from_params(cls, params: Sequence[int], label: str = "") -> Self:
        """Build one from its integers in wire order; ProtocolError when their count is wrong."""
        check_command_count(cls, params)
        return cls(*params)


@dataclass(frozen=True)
class Telem(MessageBase):
    """``TELEM,P,MASK``: a TEL line every P ms (0 = off) with the field groups of MASK."""

    period_ms: int
    mask: int
    TYPE: ClassVar[int] = codes.TELEM

    def params(self) -> tuple[int, ...]:
        """P, MASK in wire order."""
        return (self.period_ms, self.mask)

    @classmethod
    def from_params(cls, params: Sequence[int], label: str = "") -> Self:
        """Build one from its integers in wire order; ProtocolError when their count is wrong."""
        check_command_count(cls, params)
        return cls(*params)


@dataclass(frozen=True)
class Status(NoParams):
    """``STATUS``: ask for a :class:`StatusReply`."""

    TYPE: ClassVar[int] = codes.STATUS


@dataclass(frozen=True)
class Hello(MessageBase):
    """``HELLO`` or ``HELLO,V1,...,Vn``: ask for a :class:`HelloReply`; optionally list the
    protocol versions the host speaks (the controller answers with the highest common one)."""

    versions: tuple[int, ...] = ()
    TYPE: ClassVar[int] = codes.HELLO

    def __post_init__(self) -> None:
        object.__setattr__(self, "versions", tuple(self.versions))

    def params(self) -> tuple[int, ...]:
        """The versions, in wire order."""
        return self.versions

    @classmethod
    def from_params(cls, params: Sequence[int], label: str = "") -> Self:
        """Build one from the versions offered; ProtocolError when their count is wrong."""
        check_command_count(cls, params)
        return cls(tuple(params))


@dataclass(frozen=True)
class Cal(MessageBase):
    """``CAL,T,I,X,Y``: write knot I of calibration table T (codes.CAL_*); Y is a factor x 1000."""

    table: int
    index: int
    x: int
    y: int
    TYPE: ClassVar[int] = codes.CAL

    def params(self) -> tuple[int, ...]:
        """T, I, X, Y in wire order."""
        return (self.table, self.index, self.x, self.y)

    @classmethod
    def from_params(cls, params: Sequence[int], label: str = "") -> Self:
        """Build one from its integers in wire order; ProtocolError when their count is wrong."""
        check_command_count(cls, params)
        return cls(*params)


@dataclass(frozen=True)
class Ack(NoParams):
    """Binary only: the host acknowledges the event frame with the same seq."""

    TYPE: ClassVar[int] = codes.ACK
