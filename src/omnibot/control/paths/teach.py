"""Teach: sample a path from the poses a robot reports while it is driven or pushed by hand.

Seed 002 samples "by manually moving the robot along a curve path while simultaneously storing the
coordinates ... periodically at high frequency", optionally with the orientation and the speed at
each point. :class:`PathRecorder` takes poses as they come (from an estimator, any rate) and keeps
one every ``every`` seconds (``by="time"``) or metres (``by="distance"``; a turn in place of more
than ``turn`` rad also makes a sample, so turns are not lost), plus the first and the last pose.
The speed stored with a sample is the mean speed since the previous sample.
"""

from __future__ import annotations

import math

import numpy as np

from omnibot.control.paths.path import Path

SAMPLING = ("time", "distance")


class PathRecorder:
    """Keeps poses at a time or distance interval; :meth:`path` returns what was recorded."""

    def __init__(
        self,
        by: str = "distance",
        every: float = 0.02,
        *,
        store_heading: bool = True,
        store_speed: bool = False,
        turn: float = math.radians(5),
    ) -> None:
        if by not in SAMPLING:
            raise ValueError(f"sampling must be 'time' or 'distance', got {by!r}")
        if not every > 0:
            raise ValueError(f"sampling interval must be positive, got {every}")
        self.by = by
        self.every = every
        self.store_heading = store_heading
        self.store_speed = store_speed
        self.turn = turn
        self._rows: list[tuple[float, float, float, float, float]] = []
        self._last: tuple[float, float, float, float] | None = None
        self._pending: tuple[float, float, float, float] | None = None

    def __len__(self) -> int:
        return len(self._rows) + (1 if self._pending is not None else 0)

    def add(self, t: float, x: float, y: float, theta: float) -> bool:
        """Offer a pose at time ``t``; True if it was kept as a sample."""
        if self._last is None:
            self._keep(t, x, y, theta, 0.0)
            return True
        t0, x0, y0, th0 = self._last
        if self.by == "time":
            due = t - t0 >= self.every - 1e-9
        else:
            due = math.hypot(x - x0, y - y0) >= self.every - 1e-9 or abs(theta - th0) >= self.turn
        if due:
            dt = t - t0
            speed = math.hypot(x - x0, y - y0) / dt if dt > 0 else 0.0
            self._keep(t, x, y, theta, speed)
            self._pending = None
            return True
        self._pending = (t, x, y, theta)
        return False

    def _keep(self, t: float, x: float, y: float, theta: float, speed: float) -> None:
        self._rows.append((t, x, y, theta, speed))
        self._last = (t, x, y, theta)

    def path(self) -> Path:
        """The samples so far (plus the last pose offered) as a path starting at t = 0."""
        rows = list(self._rows)
        if self._pending is not None and self._last is not None:
            t, x, y, th = self._pending
            t0, x0, y0, _ = self._last
            if math.hypot(x - x0, y - y0) > 1e-4 or t > t0:
                dt = t - t0
                rows.append((t, x, y, th, math.hypot(x - x0, y - y0) / dt if dt > 0 else 0.0))
        if len(rows) < 2:
            raise ValueError(f"recorded {len(rows)} pose(s); a path needs at least two")
        a = np.array(rows, dtype=float)
        theta = a[:, 3] if self.store_heading else np.full(len(a), a[0, 3])
        return Path(a[:, 1], a[:, 2], theta, a[:, 0] - a[0, 0], a[:, 4] if self.store_speed else None)
