"""Scans meeting the odometry of their time: the runtime's side of a scan consumer.

:class:`ScanFeed` is a runtime sink (:mod:`omnibot.runtime.sinks`). Every cycle it keeps the
runtime's estimate (the fused wheel and gyro odometry) as the odometry trajectory, takes the scans
completed since the last cycle from a :class:`~omnibot.lidar.reader.ScanSource` (None: the
runtime's scanner, the cycle's ``scans``), and hands each on with the odometry pose at its first
ray and at its last (interpolated between the cycles around them; a scan newer than the last
estimate waits for the next cycle), in the runtime's thread or, ``threaded``, a worker's. Its
subclasses (:mod:`omnibot.mapping.session`) say what a scan is for: the SLAM, or localisation.
"""

from __future__ import annotations

import bisect
import contextlib
import queue
import threading
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from omnibot.mapping.deskew import scan_points
from omnibot.mapping.se2 import between, compose, wrap
from omnibot.motion import Pose2D, Twist
from omnibot.scan import Scan

FloatArray = NDArray[np.float64]

if TYPE_CHECKING:
    from omnibot.lidar import ScanSource
    from omnibot.runtime import Cycle

HISTORY = 4096
"""Odometry samples kept for interpolation (40 s at 100 Hz; scans are never that late)."""
PENDING_MAX = 64
"""Scans kept while the odometry has not caught up with them (the oldest are dropped)."""


@dataclass
class Track:
    """A trajectory being recorded: times (s) and poses."""

    stamps: list[float] = field(default_factory=list)
    poses: list[Pose2D] = field(default_factory=list)

    def add(self, stamp: float, pose: Pose2D) -> None:
        """Append a pose (times never decrease)."""
        self.stamps.append(stamp)
        self.poses.append(pose)

    def __len__(self) -> int:
        return len(self.stamps)


def interpolate(stamps: list[float], poses: list[Pose2D], t: float) -> Pose2D | None:
    """The pose at ``t`` between the samples around it (linear, heading the short way round); None
    when ``t`` is outside the samples."""
    if not stamps or t < stamps[0] or t > stamps[-1]:
        return None
    i = bisect.bisect_left(stamps, t)
    if stamps[i] == t or i == 0:
        return poses[i]
    t0, t1 = stamps[i - 1], stamps[i]
    a, b = poses[i - 1], poses[i]
    k = (t - t0) / (t1 - t0)
    return Pose2D(a.x + k * (b.x - a.x), a.y + k * (b.y - a.y), wrap(a.theta + k * wrap(b.theta - a.theta)))


class ScanFeed:
    """The runtime's side of a scan consumer (see the module docstring): keeps the odometry of every
    cycle, matches each scan to the odometry of its time and hands it to :meth:`_update` (in the
    runtime's thread, or a worker's with ``threaded``); ``close()`` when the run ends."""

    def __init__(self, scans: ScanSource | None, *, threaded: bool = False) -> None:
        self.scans = scans
        self.odometry = Track()
        self.received = 0
        """Scans taken from the source."""
        self.dropped = 0
        """Scans dropped: older than the odometry kept, or while too many waited."""
        self.failure: BaseException | None = None
        """Why the worker stopped (a threaded feed), else None."""
        self._history_t: list[float] = []
        self._history_p: list[Pose2D] = []
        self._pending: list[Scan] = []
        self._lock = threading.Lock()
        self._queue: queue.Queue[tuple[Scan, Pose2D] | None] | None = None
        self._worker: threading.Thread | None = None
        if threaded:
            self._queue = queue.Queue()
            self._worker = threading.Thread(
                target=self._work, name=f"omnibot-{type(self).__name__}", daemon=True
            )
            self._worker.start()

    def __call__(self, cycle: Cycle) -> None:
        """Keep the cycle's odometry; hand every scan it covers on."""
        est = cycle.estimate
        if est is not None and (not self._history_t or cycle.t > self._history_t[-1]):
            pose = Pose2D(est.x, est.y, est.theta)
            self._history_t.append(cycle.t)
            self._history_p.append(pose)
            self.odometry.add(cycle.t, pose)
            if len(self._history_t) > HISTORY:
                del self._history_t[: len(self._history_t) - HISTORY]
                del self._history_p[: len(self._history_p) - HISTORY]
        fresh = self.scans.poll() if self.scans is not None else list(cycle.scans)
        self.received += len(fresh)
        self._pending.extend(fresh)
        waiting: list[Scan] = []
        for scan in self._pending:
            span = scan.time_increment * max(len(scan) - 1, 0)
            odom = interpolate(self._history_t, self._history_p, scan.stamp)
            end = interpolate(self._history_t, self._history_p, scan.stamp + span) if span > 0 else odom
            if odom is not None and end is not None:
                self._keep(scan, odom, end, span)
                self._take(scan, odom)
            elif self._history_t and scan.stamp < self._history_t[0]:
                self.dropped += 1  # before the odometry began (or long gone)
            else:
                waiting.append(scan)
        if len(waiting) > PENDING_MAX:
            self.dropped += len(waiting) - PENDING_MAX
            waiting = waiting[-PENDING_MAX:]
        self._pending = waiting

    @property
    def last_odometry(self) -> Pose2D | None:
        """The latest cycle's odometry pose (None before the first estimate)."""
        return self._history_p[-1] if self._history_p else None

    def map_to_odom_now(self) -> Pose2D | None:
        """The odometry frame's pose in the map now (None while there is no map to place it in)."""
        raise NotImplementedError

    def pose_now(self) -> Pose2D | None:
        """The robot's map-frame pose now: :meth:`map_to_odom_now` composed with the latest
        odometry (None before the first odometry, or while there is no map)."""
        odom = self.last_odometry
        correction = None if odom is None else self.map_to_odom_now()
        return None if odom is None or correction is None else compose(correction, odom)

    def _keep(self, scan: Scan, start: Pose2D, end: Pose2D, span: float) -> None:
        """A scan with the odometry at its first and last rays (``span`` s apart), in the runtime's
        thread before :meth:`_update` (nothing here)."""

    def _update(self, scan: Scan, odom: Pose2D) -> None:
        raise NotImplementedError

    def _take(self, scan: Scan, odom: Pose2D) -> None:
        if self._queue is not None:
            self._queue.put((scan, odom))
        else:
            self._update(scan, odom)

    def _work(self) -> None:
        assert self._queue is not None
        while (item := self._queue.get()) is not None:
            if self.failure is not None:
                continue  # drain: it failed once, it is not asked again
            try:
                self._update(*item)
            except Exception as exc:  # kept, and told by the command: never raised in the loop
                self.failure = exc

    def close(self) -> None:
        """Finish the work (a threaded feed waits for its queue) and close the scan source."""
        if self._worker is not None and self._queue is not None:
            self._queue.put(None)
            self._worker.join()
            self._worker = None
        if self.scans is not None:
            with contextlib.suppress(Exception):
                self.scans.close()


def span_twist(start: Pose2D, end: Pose2D, span: float) -> Twist:
    """The body twist that goes from ``start`` to ``end`` in ``span`` s (zero for no span)."""
    if span <= 0:
        return Twist()
    d = between(start, end)
    return Twist(d.x / span, d.y / span, d.theta / span)


def undistorted(scan: Scan, start: Pose2D, end: Pose2D, span: float) -> FloatArray:
    """The scan's returns in the base frame at its first ray, moved by the odometry's motion from
    ``start`` to ``end`` over the revolution's ``span`` s (a spinning scanner's distortion undone)."""
    return scan_points(scan, span_twist(start, end, span))
