"""SI views of the controller's query replies: :class:`Hello` and :class:`Status`."""

from __future__ import annotations

import math
from dataclasses import dataclass

from omnibot.protocol import codes, units
from omnibot.protocol.messages import HelloReply, StatusReply


@dataclass(frozen=True)
class Hello:
    """``HELLO,<version>,<robot name>,<motors>``: what the controller is (``window``: the send
    window it announced in a binary HELLO reply, 0 from a text one)."""

    version: int
    name: str
    motors: int
    window: int = 0

    @classmethod
    def from_reply(cls, reply: HelloReply) -> Hello:
        """The client's view of a HELLO reply."""
        return cls(reply.version, reply.name, reply.motors, reply.window)


def _distance(cm: int) -> float:
    return math.copysign(math.inf, cm) if abs(cm) == codes.INF else units.from_cm(cm)


@dataclass(frozen=True)
class MoveState:
    """The remembered MOVE (the base of DELTA) in SI: m (+-inf: endless), m/s, rad, 1/m."""

    distance: float
    speed: float
    course: float
    curvature: float

    @classmethod
    def from_protocol(cls, move: tuple[int, int, int, int]) -> MoveState:
        """The remembered MOVE from its protocol integers (cm, cm/s, degrees, 1/(1000 cm)) in SI."""
        L, V, D, C = move
        return cls(_distance(L), units.from_cm(V), units.from_deg(D), units.from_curvature(C))


STATE_NAMES = {
    codes.STATE_MOVING: "moving",
    codes.STATE_IDLE: "idle",
    codes.STATE_ESTOP: "estop",
    codes.STATE_BATTERY: "battery stop",
}


@dataclass(frozen=True)
class Status:
    """The STATUS reply: state, queue, MODE bits, motor powers (raw counts), remembered MOVE."""

    state: int
    queued: int
    capacity: int
    mode: int
    powers: tuple[int, ...]
    move: MoveState

    @classmethod
    def from_reply(cls, reply: StatusReply) -> Status:
        """The client's view of a STATUS reply, in SI."""
        return cls(
            reply.state,
            reply.queued,
            reply.capacity,
            reply.mode,
            tuple(reply.powers),
            MoveState.from_protocol(reply.move),
        )

    @property
    def state_name(self) -> str:
        """``moving``, ``idle`` or ``estop`` (or the number of an unknown state)."""
        return STATE_NAMES.get(self.state, str(self.state))

    @property
    def moving(self) -> bool:
        """True while the controller executes a motion."""
        return self.state == codes.STATE_MOVING

    @property
    def idle(self) -> bool:
        """True when the controller has nothing to do."""
        return self.state == codes.STATE_IDLE

    @property
    def estop(self) -> bool:
        """True while a stop is latched: the sonar's (motion gets ERROR 40 until STOP) or the
        battery's (ERROR 44 until STOP with the voltage back up; :attr:`battery_stop`)."""
        return self.state in (codes.STATE_ESTOP, codes.STATE_BATTERY)

    @property
    def battery_stop(self) -> bool:
        """True while the battery stop is latched (state 4)."""
        return self.state == codes.STATE_BATTERY

    @property
    def simulation(self) -> bool:
        """True when the controller simulates its motors (MODE bit ``MODE_SIMULATION``)."""
        return bool(self.mode & codes.MODE_SIMULATION)

    @property
    def closed_loop(self) -> bool:
        """True when the wheel-speed loop is closed on the encoders (MODE bit ``MODE_CLOSED_LOOP``)."""
        return bool(self.mode & codes.MODE_CLOSED_LOOP)

    @property
    def binary(self) -> bool:
        """True when the link speaks binary frames (MODE bit ``MODE_BINARY``)."""
        return bool(self.mode & codes.MODE_BINARY)
