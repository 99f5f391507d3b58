"""The demo's ground truth: the pty emulator's truth file (:class:`TruthFile`) timed by the emulator's
simulated time and placed on the link's clock by the controller's TELs (:class:`ControllerClock`), or
the in-process simulator of a ``sim://`` link (:class:`TruthSource`); the world's bounds the plot
keeps to (:func:`world_bounds`).
"""

from __future__ import annotations

import bisect
import csv
from collections.abc import Sequence
from pathlib import Path
from typing import Any, Protocol

from omnibot.client import ClientRecording, Event, Telemetry
from omnibot.motion import Pose2D


class TruthFile:
    """The emulator's ``--truth`` CSV, read as it grows (it is flushed every 100 ms)."""

    def __init__(self, path: Path) -> None:
        self.path = path

    def rows(self) -> list[tuple[float, float, float, float]]:
        """Every row so far: (t, x, y, theta)."""
        try:
            with self.path.open(newline="") as f:
                return [
                    (float(r["t"]), float(r["x"]), float(r["y"]), float(r["theta"]))
                    for r in csv.DictReader(f)
                    if r.get("theta")
                ]
        except (OSError, ValueError):
            return []

    def latest(self) -> Pose2D | None:
        """The last row's pose, None while the file has none."""
        rows = self.rows()
        return Pose2D(*rows[-1][1:]) if rows else None


Bounds = tuple[tuple[float, float], tuple[float, float]]


class DemoRecording(ClientRecording, Protocol):
    """``--log``'s recording as the demo uses it (:class:`omnibot.logs.recording.Recording`): the
    clients it opens and, on the pty emulator, the truth of the emulator's file."""

    def truth_rows(self, rows: Sequence[tuple[float, float, float, float]]) -> int:
        """Ground truth rows ``t, x, y, theta`` on the link's clock into the log."""


class ControllerClock:
    """The controller's clock placed on the link's by its TELs (the pty emulator's truth file is timed
    by the emulator's simulated time, which is its firmware's clock)."""

    def __init__(self) -> None:
        self.pairs: list[tuple[float, float]] = []
        """(controller time, link time minus controller time) of each TEL (a demo's few thousand)."""

    def __call__(self, event: Event) -> None:
        """A client listener: each TEL's pair of times (a clock that went back is a restart: anew)."""
        if isinstance(event, Telemetry):
            if self.pairs and event.controller_time < self.pairs[-1][0]:
                self.pairs.clear()
            self.pairs.append((event.controller_time, event.time - event.controller_time))

    def link_time(self, controller_time: float) -> float | None:
        """The link time of an instant on the controller's clock, by the TELs sent either side of it:
        their offsets interpolated (a TEL's delay on the line, a few ms, is the error; an emulator
        that falls behind the wall clock, as a loaded one does, moves the offset, so it is taken at
        each instant, not once); before the first or after the last TEL, that TEL's; None without."""
        pairs = self.pairs
        if not pairs:
            return None
        i = bisect.bisect_left(pairs, (controller_time,))
        if i == 0 or i == len(pairs):
            return controller_time + pairs[min(i, len(pairs) - 1)][1]
        (c0, o0), (c1, o1) = pairs[i - 1], pairs[i]
        share = (controller_time - c0) / (c1 - c0) if c1 > c0 else 0.0
        return controller_time + o0 + share * (o1 - o0)

    def place(
        self, rows: Sequence[tuple[float, float, float, float]]
    ) -> list[tuple[float, float, float, float]]:
        """``rows`` (t, x, y, theta) with ``t`` on the link's clock (none without a TEL)."""
        placed = [(self.link_time(t), x, y, th) for t, x, y, th in rows]
        return [(t, x, y, th) for t, x, y, th in placed if t is not None]


class TruthSource:
    """Ground truth: the emulator's CSV file, or the in-process simulator of a ``sim://`` link."""

    def __init__(self, file: TruthFile | None, bounds: Bounds | None, simulator: Any = None) -> None:
        self.file = file
        self.bounds = bounds
        self._sim = simulator
        self._trail: list[tuple[float, float, float, float]] = []
        if simulator is not None:
            simulator.add_listener(
                lambda snap: self._trail.append((snap.t, snap.x, snap.y, snap.theta)), period=0.01
            )

    def rows(self) -> list[tuple[float, float, float, float]]:
        """Every true pose so far as ``(t, x, y, theta)``."""
        return self.file.rows() if self.file is not None else self._trail

    def __call__(self) -> Pose2D | None:
        """The true pose now (None without ground truth)."""
        if self._sim is not None:
            p = self._sim.pose
            return Pose2D(p.x, p.y, p.theta)
        return self.file.latest() if self.file is not None else None


def world_bounds(world: Any) -> Bounds | None:
    """The walls' bounding box (None for a world without walls)."""
    xs = [v for seg in world.segments for v in (seg[0], seg[2])]
    ys = [v for seg in world.segments for v in (seg[1], seg[3])]
    return ((min(xs), min(ys)), (max(xs), max(ys))) if xs else None
