"""The simulator's laser scanner feed: when the scanner measures, the poses its rays are cast from,
and the revolutions handed to the scan listeners.

A robot with a ``scanner`` has a :class:`~omnibot.sim.scanner.LaserScanner` (:attr:`ScanFeed.scanner`).
It measures only while someone wants scans: a scan listener is registered
(:meth:`ScanFeed.add_scan_listener`) or :attr:`ScanFeed.last_scan` has been read once; otherwise it
costs one test per step in the compiled step. While it measures, the compiled step records the
pose every SCAN_POSE_PERIOD in the simulator's own state (:func:`~omnibot.sim.kernels.pose_log`)
and says (STEP_SCAN) when a revolution is due; the revolution is then cast and measured in one
compiled call. Scan listeners are called from the simulator's step (the stepping thread, in
simulated time) with every revolution completed, as an :class:`omnibot.scan.Scan`. The scanner
sees the world's walls and obstacles, never its own robot. In a fleet it sees the other robots
where they were at each ray's time: every robot's step records its pose, and the fleet reads the
logs side by side and flushes the scanners (:attr:`ScanFeed.scan_driver`). Bodies given by a simulator's ``neighbours`` of another
kind are seen as they stand when the rays are cast (every 20 ms then).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Self

import numpy as np
from numpy.typing import NDArray

from omnibot.errors import SimulationError
from omnibot.robot import RobotDescription
from omnibot.scan import Scan
from omnibot.sim.clock import SimClock
from omnibot.sim.kernels import layout
from omnibot.sim.scanner import SCAN_POSE_PERIOD, LaserScanner, PoseLog
from omnibot.sim.truth import ScanListener
from omnibot.sim.world import World

FloatArray = NDArray[np.float64]

SCAN_OTHERS_EVERY = 0.02
"""s: how often a scanner with a simulator's ``neighbours`` but no :attr:`ScanFeed.scan_driver` casts
the rays due, so that it sees those bodies at most this long after the rays' times (a fleet's
scanners see the others at the rays' times; alone, a scanner casts once per revolution)."""


class ScanFeed:
    """:class:`~omnibot.sim.simulator.Simulator`'s laser scanner, switched on while someone wants
    scans, and fed the poses (by the simulator's step, :meth:`_scan_tick`, or by a fleet)."""

    robot: RobotDescription
    world: World
    clock: SimClock
    dt: float
    _dt_us: int
    _pose_row: FloatArray
    _si: NDArray[np.int64]
    _log_stride_us: int
    pose_log: Callable[[], tuple[FloatArray, NDArray[np.int64]]]
    _pose_log_start: Callable[[int], None]
    _pose_log_stop: Callable[[], None]
    neighbours: Callable[[], FloatArray] | None
    scan_driver: Callable[[Self], None] | None
    """Who records the poses and flushes the scanner instead of the simulator (a fleet: see
    :meth:`set_scan_driver`); called with the simulator when its scanner starts or stops."""

    def _init_scan(self, scanner: LaserScanner | None) -> None:
        """Hold ``scanner`` (None: the robot has none), off, with nobody wanting scans."""
        self._scanner = scanner
        self.scan_driver = None
        self._scan_listeners: list[ScanListener] = []
        self._scan_asked = False
        self._scan_on = False
        self._scan_due_us = 0
        self._scan_log = PoseLog([self], self._log_stride_us / 1e6)

    @property
    def scanner(self) -> LaserScanner | None:
        """The robot's laser scanner, or None if its description has none."""
        return self._scanner

    @property
    def last_scan(self) -> Scan | None:
        """The latest complete revolution of the scanner (None before the first, or without a scanner).

        Reading it switches the scanner on for good (it stays on: someone wants scans), so the first
        read returns None and a revolution is there one to two revolutions of simulated time later.
        """
        if self._scanner is None:
            return None
        if not self._scan_asked:
            self._scan_asked = True
            self._scan_switch()
        return self._scanner.last

    def add_scan_listener(self, fn: ScanListener) -> None:
        """Call ``fn(scan)`` with every revolution the scanner completes from now on (in simulated
        time, from the thread that steps the simulator). SimulationError if the robot has no scanner."""
        if self._scanner is None:
            raise SimulationError(f"robot '{self.robot.name}' has no scanner (add a 'scanner:' section)")
        self._scan_listeners = [*self._scan_listeners, fn]  # a new list: a flush calls the one it began with
        self._scan_switch()

    def remove_scan_listener(self, fn: ScanListener) -> None:
        """Stop calling ``fn`` (no error if it was not registered)."""
        self._scan_listeners = [f for f in self._scan_listeners if f != fn]
        self._scan_switch()

    def _scan_switch(self: Self) -> None:
        """Start or stop the scanner as someone wants scans or nobody does."""
        sc = self._scanner
        if sc is None:
            return
        want = bool(self._scan_listeners) or self._scan_asked
        if want == self._scan_on:
            return
        self._scan_on = want
        if want:
            now_us = self.clock.ticks_us()
            sc.start(now_us / 1e6)
            self._scan_due_us = self._due_us(sc.due)
            if self.scan_driver is None:
                self._pose_log_start(now_us)
                self._scan_log = PoseLog([self], self._log_stride_us / 1e6, now_us)
                self._si[layout.I_LOG_FLUSH] = self._scan_log.flush_at(self._scan_due_us)
        else:
            sc.stop()
            if self.scan_driver is None:
                self._pose_log_stop()
        if self.scan_driver is not None:
            self.scan_driver(self)

    def set_scan_driver(self, driver: Callable[[Self], None] | None) -> None:
        """Let ``driver`` (a fleet) record the poses and call :meth:`scan_flush` (None: the simulator
        does it). A revolution under way is dropped; the scanner goes on if someone wants scans."""
        asked, listeners = self._scan_asked, self._scan_listeners
        self._scan_asked, self._scan_listeners = False, []
        self._scan_switch()  # off under the old driver
        self.scan_driver = driver
        self._scan_asked, self._scan_listeners = asked, listeners
        self._scan_switch()  # on again under the new one

    @property
    def pose_array(self) -> FloatArray:
        """The live true pose (x, y, theta) as a read-only (3,) view (what a fleet records)."""
        view: FloatArray = self._pose_row.view()
        view.flags.writeable = False
        return view

    @staticmethod
    def _due_us(due: float) -> int:
        """A flush time in s as the first step end (whole us) at or after it."""
        return math.ceil(due * 1e6 - 1e-3)

    def scan_flush(
        self,
        now_us: int,
        poses: PoseLog,
        own: int = 0,
        bodies: tuple[FloatArray, NDArray[np.int64]] | None = None,
    ) -> int:
        """Cast the scanner's rays due by ``now_us`` with the poses of ``poses`` (this robot is body
        ``own``; ``bodies`` the outlines of all, see :meth:`LaserScanner.flush`), hand the completed
        revolutions to the scan listeners, and return when (us) the next flush is due."""
        sc = self._scanner
        if sc is None or not self._scan_on:
            return 2**62
        segments = self.world.segments
        others = self.neighbours() if self.neighbours is not None and self.scan_driver is None else None
        if others is not None and len(others):
            segments = np.concatenate((segments, others))
        scans = sc.flush(now_us / 1e6, segments, poses, own, bodies)
        due = self._due_us(sc.due)
        if others is not None:
            due = min(due, now_us + round(SCAN_OTHERS_EVERY * 1e6))
        self._scan_due_us = due
        for scan in scans:
            for fn in self._scan_listeners:
                fn(scan)
        return due

    def _scan_tick(self, now_us: int) -> None:
        """Flush the scanner (the robot alone: its step has just recorded the pose) and trim the log."""
        assert self._scanner is not None
        log = self._scan_log
        self.scan_flush(now_us, log)
        log.trim(self._scanner.needs_from)
        self._si[layout.I_LOG_FLUSH] = log.flush_at(self._scan_due_us)


__all__ = ["SCAN_OTHERS_EVERY", "SCAN_POSE_PERIOD", "ScanFeed"]
