"""What the simulator tells of the true robot: :class:`Snapshot` (its time, pose and twist),
:class:`CollisionEvent`, the listener types, and :class:`TruthRecorder` (a listener writing
``t,x,y,theta`` CSV)."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import IO

from omnibot.motion import Pose2D, Twist
from omnibot.scan import Scan


@dataclass(frozen=True, slots=True)
class Snapshot:
    """Ground truth at one instant: time (s), world pose (m, m, rad, continuous), body twist."""

    t: float
    x: float
    y: float
    theta: float
    vx: float
    vy: float
    w: float

    @property
    def pose(self) -> Pose2D:
        """The position and heading (m, m, rad)."""
        return Pose2D(self.x, self.y, self.theta)

    @property
    def twist(self) -> Twist:
        """The body-frame velocity (m/s, m/s, rad/s), as the class says."""
        return Twist(self.vx, self.vy, self.w)


@dataclass(frozen=True, slots=True)
class CollisionEvent:
    """The robot started touching a wall or obstacle.

    ``x, y`` is the contact point (world, m), ``normal`` the direction the wall pushes the robot,
    ``speed`` the approach speed of the contact point along it (m/s), ``owner`` the world item.
    """

    time: float
    x: float
    y: float
    normal: tuple[float, float]
    depth: float
    speed: float
    owner: str
    pose: Pose2D


Listener = Callable[[Snapshot], None]
CollisionListener = Callable[[CollisionEvent], None]
ScanListener = Callable[[Scan], None]


class TruthRecorder:
    """A listener writing ground truth as CSV ``t,x,y,theta`` (s, m, m, rad; theta not wrapped).

    Writes one row per ``period`` seconds of simulated time (on the grid 0, period, 2 period...),
    whatever rate it is called at, and flushes the stream every ``flush_every`` simulated seconds
    (so a reader following the file in real time lags at most that much). Give it a path (opened and
    closed by the recorder) or an open text stream (left open).
    """

    def __init__(self, file: str | Path | IO[str], period: float = 0.01, flush_every: float = 0.1) -> None:
        if period <= 0:
            raise ValueError(f"period must be > 0, got {period}")
        self.period = period
        self.flush_every = flush_every
        self._next_flush = flush_every
        if isinstance(file, str | Path):
            self._stream: IO[str] = open(file, "w", encoding="utf-8", newline="")  # noqa: SIM115
            self._owned = True
        else:
            self._stream, self._owned = file, False
        self._stream.write("t,x,y,theta\n")
        self._next = 0
        self.rows = 0
        self.closed = False

    def __call__(self, snap: Snapshot) -> None:
        """Write a row if a new period has begun (does nothing once closed)."""
        k = math.floor(snap.t / self.period + 1e-6)
        if k < self._next or self.closed:
            return
        self._next = k + 1
        self._stream.write(f"{snap.t:.6f},{snap.x:.6f},{snap.y:.6f},{snap.theta:.6f}\n")
        self.rows += 1
        if snap.t >= self._next_flush:
            self._stream.flush()
            self._next_flush = snap.t + self.flush_every

    def close(self) -> None:
        """Flush, close the file if this writer opened it, and ignore later rows."""
        if self.closed:
            return
        self.closed = True
        if self._owned:
            self._stream.close()
        else:
            self._stream.flush()

    def __enter__(self) -> TruthRecorder:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
