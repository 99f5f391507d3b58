"""What the controller says unasked, controller -> host: RANGE, WARN, IDLE and TEL (ERROR as an event
is the reply's class); each a frozen dataclass (see :mod:`omnibot.protocol.messages`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, ClassVar, Self

from omnibot.errors import ProtocolError
from omnibot.protocol import codes
from omnibot.protocol.msgbase import Coded, MessageBase, NoParams, check_count


@dataclass(frozen=True)
class Range(MessageBase):
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
        check_count(cls, params, 2)
        return cls(*params)


@dataclass(frozen=True)
class Warn(Coded):
    """``WARN,<code>,<text>``: a warning of the motion or sensor logic."""

    TYPE: ClassVar[int] = codes.WARN


@dataclass(frozen=True)
class Idle(NoParams):
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
class Telemetry(MessageBase):
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
