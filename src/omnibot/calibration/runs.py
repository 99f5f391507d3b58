"""What a calibration run is and what it measured (plain data, no I/O).

A run has a kind (:data:`STRAIGHT`, :data:`ROTATE`, :data:`TURN`, :data:`SQUARE`) and a
:class:`RunInfo` the truth strategies read; a strategy turns it into a :class:`Motion` (the
displacement in the body frame at the run's start, and the angle turned); the runner keeps both,
with the robot's own sensors' view, as a :class:`RunResult`. The fits read nothing else.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

STRAIGHT = "straight"
ROTATE = "rotate"
TURN = "turn"
SQUARE = "square"


@dataclass(frozen=True)
class RunInfo:
    """What a run is, for strategies that need to know (sonar: the course) or to ask (tape)."""

    kind: str
    """``straight`` (translation), ``rotate`` (in place), ``turn`` (curved move), ``square``."""
    text: str
    course: float | None = None
    """Commanded course of a straight run, rad (body frame)."""


@dataclass(frozen=True)
class Motion:
    """What a run did, in the body frame at its start; None where the source cannot tell."""

    x: float | None = None
    """m forward."""
    y: float | None = None
    """m to the left."""
    theta: float | None = None
    """rad turned, counter-clockwise positive."""
    along: float | None = None
    """m along the commanded course, when only that is known (sonar, a tape length)."""
    source: str = ""

    @property
    def distance(self) -> float | None:
        """Length of the displacement (or the distance along the course when that is all there is)."""
        if self.x is not None and self.y is not None:
            return math.hypot(self.x, self.y)
        return self.along

    @property
    def path(self) -> float | None:
        """Length of the path, taking it as a circular arc when the body turned: a robot whose body
        turns at a constant rate while it translates at a constant body-frame velocity drives an arc,
        whose length is ``chord * (theta / 2) / sin(theta / 2)``."""
        chord = self.distance
        if chord is None or self.theta is None or self.x is None:
            return chord
        half = 0.5 * abs(self.theta)
        if half < 1e-6:
            return chord
        return chord * half / math.sin(half) if half < 0.95 * math.pi else None

    @property
    def direction(self) -> float | None:
        """Direction of the displacement in the start body frame, rad."""
        if self.x is None or self.y is None or (self.x == 0.0 and self.y == 0.0):
            return None
        return math.atan2(self.y, self.x)


def relative(x0: float, y0: float, th0: float, x1: float, y1: float, th1: float, source: str) -> Motion:
    """The motion from pose 0 to pose 1 (world frame) expressed in pose 0's body frame."""
    dx, dy = x1 - x0, y1 - y0
    c, s = math.cos(th0), math.sin(th0)
    return Motion(x=c * dx + s * dy, y=-s * dx + c * dy, theta=th1 - th0, source=source)


@dataclass(frozen=True)
class RunResult:
    """One run: what was commanded, what the truth and the robot's own sensors say it did."""

    kind: str
    group: str
    """``course:<folded deg>``, ``rotation``, ``deadband:...``, ``turn``, ``square``, ``gyro``."""
    command: str
    duration: float
    """s the motors were driven (POWER T, MOVE L/V, ROTATE A/F)."""
    truth: Motion | None
    odometry: Motion | None = None
    gyro: float | None = None
    """Heading change (rad) integrated by the controller from its gyro, bias included."""
    gyro_time: float | None = None
    """Controller seconds between the gyro marks."""
    power: int | None = None
    course_deg: float | None = None
    folded_deg: float | None = None
    sign: int = 1
    commanded: float | None = None
    """Commanded amount of a MOVE (m) or a turn (rad)."""
    p_arg: float | None = None
    """The firmware's power argument of the calibrated part (K times the busiest rim speed)."""
    warnings: tuple[int, ...] = ()
    counts: tuple[int, ...] | None = None
    """The controller's wheel encoder counts at the start (from telemetry), when it has encoders."""
    correction: float = 0.0
    """m added to a straight run's path by a later fit (the idle wheels' roller drag, rollers.py)."""

    @property
    def amount(self) -> float | None:
        """Path length (m, straight: the arc when the body turned, see :attr:`Motion.path`, plus
        :attr:`correction`) or angle (rad, rotations and turns, signed by the command) achieved."""
        if self.truth is None:
            return None
        if self.kind == STRAIGHT:
            path = self.truth.path
            return None if path is None else path + self.correction
        return None if self.truth.theta is None else self.sign * self.truth.theta

    def as_dict(self) -> dict[str, Any]:
        """The run as plain data (for the JSON run log), unset fields left out."""
        out: dict[str, Any] = {
            k: v for k, v in self.__dict__.items() if k not in ("truth", "odometry") and v is not None
        }
        for key in ("truth", "odometry"):
            m = getattr(self, key)
            if m is not None:
                out[key] = {k: v for k, v in m.__dict__.items() if v is not None}
        out["warnings"] = list(self.warnings)
        return out
