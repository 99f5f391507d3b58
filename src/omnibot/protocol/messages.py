"""Typed messages of the motor-controller protocol: one frozen dataclass per command, reply and event.

Messages carry protocol integers in the protocol's units (cm, cm/s, degrees, degrees/s,
1/(1000 cm), ms, raw power); :mod:`omnibot.protocol.units` converts to and from SI. Both codecs
work from the same two methods of every message:

* ``params()``: its integers in wire order (the text parameters; the binary varints);
* ``label()``: its text field (ERROR/WARN text, robot name), "" for the others;

and rebuild it with ``Class.from_params(params, label)``, which raises :class:`ProtocolError` when
the count is wrong. ``TYPE`` is the message's id in :mod:`omnibot.protocol.codes` (binary type).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, ClassVar, Self, TypeGuard

from omnibot.errors import ProtocolError
from omnibot.protocol import codes


def _count(cls: type, params: Sequence[int], low: int, high: int | None = None) -> None:
    high = low if high is None else high
    if not low <= len(params) <= high:
        want = str(low) if low == high else f"{low}..{high}"
        raise ProtocolError(f"{cls.__name__} takes {want} integers, got {len(params)}")


def _command_count(cls: type[_Message], params: Sequence[int]) -> None:
    _count(cls, params, *codes.PARAM_COUNTS[cls.TYPE])


class _Message:
    """Behaviour shared by every message (not a message itself)."""

    TYPE: ClassVar[int]
    __slots__ = ()

    @property
    def keyword(self) -> str:
        """The text keyword (``MOVE``, ``OK``, ...)."""
        return codes.KEYWORDS[self.TYPE]

    def params(self) -> tuple[int, ...]:
        """The message's integers in wire order."""
        return ()

    def label(self) -> str:
        """The message's text field ("" if it has none)."""
        return ""


class _NoParams(_Message):
    __slots__ = ()

    @classmethod
    def from_params(cls, params: Sequence[int], label: str = "") -> Self:
        _count(cls, params, 0)
        return cls()


# --- commands, host -> controller ------------------------------------------------------------------
@dataclass(frozen=True)
class Move(_Message):
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
        _command_count(cls, params)
        return cls(*params)


@dataclass(frozen=True)
class Rotate(_Message):
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
        _command_count(cls, params)
        return cls(*params)


@dataclass(frozen=True)
class Delta(_Message):
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
        _command_count(cls, params)
        return cls(*params)


@dataclass(frozen=True)
class Stop(_NoParams):
    """``STOP``: motors off, queue cleared, remembered MOVE reset, latched emergency stop released."""

    TYPE: ClassVar[int] = codes.STOP


@dataclass(frozen=True)
class Power(_Message):
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
        _command_count(cls, params)
        return cls(params[0], tuple(params[1:]))


@dataclass(frozen=True)
class Vel(_Message):
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
        _command_count(cls, params)
        if len(params) == 6:
            raise ProtocolError("Vel takes 4, 5 or 7 integers, got 6")
        vx, vy, w, t = params[:4]
        if len(params) == 7:
            return cls(vx, vy, w, t, body=(params[4], params[5], params[6]))
        return cls(vx, vy, w, t, params[4] if len(params) == 5 else 0)


@dataclass(frozen=True)
class Mode(_Message):
    """``MODE,M``: mode bits (codes.MODE_SIMULATION, MODE_CLOSED_LOOP, MODE_BINARY)."""

    mask: int
    TYPE: ClassVar[int] = codes.MODE

    def params(self) -> tuple[int, ...]:
        """The mode mask alone."""
        return (self.mask,)

    @classmethod
    def from_params(cls, params: Sequence[int], label: str = "") -> Self:
        """Build one from its integers in wire order; ProtocolError when their count is wrong."""
        _command_count(cls, params)
        return cls(*params)


@dataclass(frozen=True)
class Sonar(_Message):
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
        _command_count(cls, params)
        return cls(*params)


@dataclass(frozen=True)
class Telem(_Message):
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
        _command_count(cls, params)
        return cls(*params)


@dataclass(frozen=True)
class Status(_NoParams):
    """``STATUS``: ask for a :class:`StatusReply`."""

    TYPE: ClassVar[int] = codes.STATUS


@dataclass(frozen=True)
class Hello(_Message):
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
        _command_count(cls, params)
        return cls(tuple(params))


@dataclass(frozen=True)
class Cal(_Message):
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
        _command_count(cls, params)
        return cls(*params)


@dataclass(frozen=True)
class Ack(_NoParams):
    """Binary only: the host acknowledges the event frame with the same seq."""

    TYPE: ClassVar[int] = codes.ACK


# --- replies, controller -> host -------------------------------------------------------------------
@dataclass(frozen=True)
class Ok(_NoParams):
    """``OK``: the command was accepted."""

    TYPE: ClassVar[int] = codes.OK


@dataclass(frozen=True)
class _Coded(_Message):
    """A code with a text: ERROR and WARN."""

    code: int
    text: str = ""

    @property
    def description(self) -> str:
        """The text, or the standard text of the code when the controller sent none."""
        return self.text or codes.TEXTS.get(self.code, "")

    def params(self) -> tuple[int, ...]:
        return (self.code,)

    def label(self) -> str:
        return self.text

    @classmethod
    def from_params(cls, params: Sequence[int], label: str = "") -> Self:
        _count(cls, params, 1)
        return cls(params[0], label)


@dataclass(frozen=True)
class ErrorReply(_Coded):
    """``ERROR,<code>,<text>``: a rejected command, or (as an event) a fault of the motion logic."""

    TYPE: ClassVar[int] = codes.ERROR


@dataclass(frozen=True)
class HelloReply(_Message):
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
        _count(cls, params, 3)
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
class StatusReply(_Message):
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
        _count(cls, params, 8, 8 + 32)
        p = tuple(params)
        move = (p[-4], p[-3], p[-2], p[-1])
        return cls(p[0], p[1], p[2], p[3], p[4:-4], move)


# --- events, controller -> host --------------------------------------------------------------------
@dataclass(frozen=True)
class Range(_Message):
    """``RANGE,<sonar>,<cm>``: a sonar reading met its configured band."""

    sonar: int
    cm: int
    TYPE: ClassVar[int] = codes.RANGE

    def params(self) -> tuple[int, ...]:
        """Sonar index and range (cm) in wire order."""
        return (self.sonar, self.cm)

    @classmethod
    def from_params(cls, params: Sequence[int], label: str = "") -> Self:
        """Build one from sonar index and range; ProtocolError unless two integers."""
        _count(cls, params, 2)
        return cls(*params)


@dataclass(frozen=True)
class Warn(_Coded):
    """``WARN,<code>,<text>``: a warning of the motion or sensor logic."""

    TYPE: ClassVar[int] = codes.WARN


@dataclass(frozen=True)
class Idle(_NoParams):
    """``IDLE``: the queue ran empty and the motors stopped."""

    TYPE: ClassVar[int] = codes.IDLE


# TEL field groups in wire order: (mask bit, attribute, counted) - counted groups carry n first.
TEL_GROUPS: tuple[tuple[int, str, bool], ...] = (
    (codes.TEL_POWER, "powers", True),
    (codes.TEL_ENCODERS, "encoders", True),
    (codes.TEL_TRACKING, "tracking", True),
    (codes.TEL_GYRO, "gyro_rate", False),
    (codes.TEL_HEADING, "heading", False),
    (codes.TEL_BATTERY, "battery_mv", False),
    (codes.TEL_QUEUE, "queue", False),
    (codes.TEL_SONAR, "ranges", True),
)


@dataclass(frozen=True)
class Telemetry(_Message):
    """``TEL,<t_ms>,<mask>,<groups...>``: one telemetry sample; absent groups are None.

    ``mask`` is derived from the groups present. Units: powers raw, encoder and tracking counts
    cumulative signed 32-bit, gyro rate 0.01 deg/s, heading 0.01 deg (not wrapped), battery mV,
    queue (state, queued), ranges cm (-1 = no reading).
    """

    t_ms: int
    powers: tuple[int, ...] | None = None
    encoders: tuple[int, ...] | None = None
    tracking: tuple[int, ...] | None = None
    gyro_rate: int | None = None
    heading: int | None = None
    battery_mv: int | None = None
    queue: tuple[int, int] | None = None
    ranges: tuple[int, ...] | None = None
    TYPE: ClassVar[int] = codes.TEL

    def __post_init__(self) -> None:
        for name in ("powers", "encoders", "tracking", "queue", "ranges"):
            value = getattr(self, name)
            if value is not None:
                object.__setattr__(self, name, tuple(value))
        if self.queue is not None and len(self.queue) != 2:
            raise ProtocolError(f"Telemetry.queue needs (state, queued), got {self.queue}")

    @property
    def mask(self) -> int:
        """The TEL mask bits of the groups present."""
        return sum(bit for bit, name, _ in TEL_GROUPS if getattr(self, name) is not None)

    def params(self) -> tuple[int, ...]:
        """Time (ms), mask, then each group present in ``TEL_GROUPS`` order (counted groups led by their
        length)."""
        out = [self.t_ms, self.mask]
        for _, name, counted in TEL_GROUPS:
            value = getattr(self, name)
            if value is None:
                continue
            if counted:
                out.append(len(value))
            out.extend(value if isinstance(value, tuple) else (value,))
        return tuple(out)

    @classmethod
    def from_params(cls, params: Sequence[int], label: str = "") -> Self:
        """Parse the groups in bit order; fields of unknown (higher) mask bits are ignored."""
        if len(params) < 2:
            raise ProtocolError("TEL needs t_ms and mask")
        t_ms, mask = params[0], params[1]
        p = list(params[2:])
        values: dict[str, Any] = {}
        for bit, name, counted in TEL_GROUPS:
            if not mask & bit:
                continue
            n = 2 if name == "queue" else 1
            if counted:
                if not p or not 0 <= p[0] <= len(p) - 1:
                    raise ProtocolError(f"TEL group {name}: bad count")
                n = p.pop(0)
            if len(p) < n:
                raise ProtocolError(f"TEL group {name}: {n} fields needed, {len(p)} left")
            group, p = p[:n], p[n:]
            values[name] = tuple(group) if counted or name == "queue" else group[0]
        if p and not mask & ~codes.TEL_MASK:
            raise ProtocolError(f"TEL: {len(p)} fields left over")
        return cls(t_ms, **values)


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
