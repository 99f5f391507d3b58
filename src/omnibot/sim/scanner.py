"""A simulated spinning 2D laser scanner (an RPLIDAR by default): rays cast as the revolution turns.

The scanner is fed the robot's true pose after every simulator step (:meth:`LaserScanner.record`)
and casts the rays that have come due when asked (:meth:`LaserScanner.flush`), each from the pose
the robot had at that ray's own time (linear between the recorded steps): a robot that moves or
turns during a revolution gets a distorted scan, as a real spinning scanner's is. Nothing is
simulated twice: the poses are those the physics already stepped through.

Revolution ``k`` starts at simulated time ``k / rate_hz``; its ray ``i`` is measured
``i * time_increment`` later (``period / rays``; 0 with ``motion_distortion`` off: every ray at the
revolution's start) and points at ``i * angle_increment`` in the scanner frame, where the increment
is negative for a clockwise scanner (the RPLIDAR's way): the scan keeps the order the rays were
measured in and gives angles counter-clockwise positive, as :class:`omnibot.scan.Scan` requires.
A revolution is delivered as a :class:`~omnibot.scan.Scan` once its last ray's time has passed.

Each range is the true distance to the nearest wall, obstacle or other body plus
N(0, noise_std + noise_fraction * distance), quantised to ``resolution``; ``inf`` for a dropout or
a return outside [range_min, range_max]. The noise of revolution ``k`` is a fixed slice of the
scanner's own random stream (``3 * rays`` uniform draws per revolution, the stream jumped ahead to
revolution ``k``), so a revolution's ranges are the same whenever the scanner was switched on and
however often it was flushed, and no other sensor's stream changes.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from omnibot.motion import Pose2D
from omnibot.robot.description import ScannerSpec
from omnibot.scan import Scan
from omnibot.sim import kernels

FloatArray = NDArray[np.float64]

_EPS = 1e-9


class LaserScanner:
    """One robot's scanner: a :class:`~omnibot.robot.description.ScannerSpec`, a seed, the step dt."""

    def __init__(self, spec: ScannerSpec, seed: int, key: int, dt: float) -> None:
        self.spec = spec
        self.dt = dt
        n = spec.rays
        self.period = spec.period
        self.time_increment = self.period / n if spec.motion_distortion else 0.0
        self.mount = Pose2D(spec.x, spec.y, spec.yaw)
        self.angles: FloatArray = np.arange(n, dtype=np.float64) * spec.angle_increment
        """Direction of every ray in the scanner frame, rad."""
        self._base_angles = np.ascontiguousarray(self.angles + spec.yaw)
        self._offsets = np.arange(n, dtype=np.float64) * self.time_increment
        self._bitgen = np.random.PCG64(np.random.SeedSequence(seed, spawn_key=(key,)))
        self._gen = np.random.Generator(self._bitgen)
        self._stream_rev = 0
        """Revolution whose draws come next from the stream."""
        stretch = 1.0 + 6.0 * spec.noise_fraction
        self._cast_range = spec.range_max * stretch + 6.0 * spec.noise_std + spec.resolution
        self._true = np.full(n, math.inf)
        self.history: list[float] = []
        """Robot poses x, y, theta (flat: 3 numbers a pose) at times ``history_start + j * dt``: those
        the rays not cast yet need."""
        self.history_start = 0.0
        self.active = False
        self.revolution = 0
        """Index of the revolution being measured."""
        self._next_ray = 0
        self.due = math.inf
        """Simulated time (s) by which :meth:`flush` has a revolution to deliver."""
        self.last: Scan | None = None
        """The latest complete revolution."""
        self.scans = 0
        """Revolutions delivered since the scanner was made."""

    def __repr__(self) -> str:
        state = f"revolution {self.revolution}" if self.active else "off"
        return (
            f"LaserScanner({self.spec.model!r}, {self.spec.rays} rays at {self.spec.rate_hz:g} Hz, {state})"
        )

    # ------------------------------------------------------------------ switching

    def start(self, t: float, pose: Sequence[float]) -> None:
        """Start measuring at simulated time ``t`` (s), the robot at ``pose`` (x, y, theta): the first
        revolution is the first that starts at or after ``t``."""
        self.active = True
        self.revolution = math.ceil(t / self.period - _EPS)
        self._next_ray = 0
        self.history = [float(c) for c in pose[:3]]
        self.history_start = t
        self.due = self.revolution * self.period + self.period

    def stop(self) -> None:
        """Stop measuring; the revolution under way is dropped."""
        self.active = False
        self.history = []
        self.due = math.inf

    def record(self, pose: Sequence[float]) -> None:
        """The robot's pose one step of dt after the last recorded one (the simulator extends
        :attr:`history` itself, the same way)."""
        self.history.extend(float(c) for c in pose[:3])

    # ------------------------------------------------------------------ measuring

    def flush(self, t: float, segments: FloatArray, others: FloatArray | None = None) -> list[Scan]:
        """Cast every ray due by simulated time ``t`` (s) against the edges ``segments`` (K, 4) and
        ``others`` (edges of other bodies now, world frame); returns the revolutions completed."""
        if not self.active:
            return []
        if others is not None and len(others):
            segments = np.concatenate((segments, others))
        done: list[Scan] = []
        n = self.spec.rays
        while True:
            stamp = self.revolution * self.period
            end = stamp + self.period
            if t >= end - _EPS:  # the whole revolution (the usual call: its end is the due time)
                last = n
            else:
                last = int(np.searchsorted(self._offsets, t - stamp + _EPS, side="right"))
            if last > self._next_ray:
                self._cast(stamp, self._next_ray, last, segments)
                self._next_ray = last
            if self._next_ray < n or t < end - _EPS:
                break
            done.append(self._deliver(stamp))
            self.revolution += 1
            self._next_ray = 0
            if t < end + self.period - _EPS:
                break  # the next revolution's rays due by now are cast with the rest of it
        nxt = self._next_ray
        self._trim(self.revolution * self.period + (self._offsets[nxt] if nxt < n else self.period))
        self.due = self.revolution * self.period + self.period
        return done

    def _cast(self, stamp: float, first: int, last: int, segments: FloatArray) -> None:
        hist = np.array(self.history, dtype=np.float64).reshape(-1, 3)
        times = self.history_start + np.arange(len(hist), dtype=np.float64) * self.dt
        kernels.scan_rays(
            stamp + self._offsets[first:last],
            self._base_angles[first:last],
            times,
            hist,
            len(hist),
            float(self.mount.x),
            float(self.mount.y),
            np.ascontiguousarray(segments, dtype=np.float64),
            float(self._cast_range),
            self._true[first:last],
        )

    def _trim(self, t_next: float) -> None:
        """Forget the poses older than the last one at or before ``t_next`` (the next ray's time)."""
        drop = math.floor((t_next - self.history_start) / self.dt + _EPS)
        drop = min(max(drop, 0), len(self.history) // 3 - 1)
        if drop > 0:
            del self.history[: 3 * drop]
            self.history_start += drop * self.dt

    def _draws(self, revolution: int) -> FloatArray:
        """The 3 * rays uniform draws of ``revolution`` (the stream jumped ahead to it)."""
        size = 3 * self.spec.rays
        if revolution > self._stream_rev:
            self._bitgen.advance((revolution - self._stream_rev) * size)
        elif revolution < self._stream_rev:  # never happens: revolutions only go forward
            raise ValueError(f"revolution {revolution} already drawn")
        self._stream_rev = revolution + 1
        return self._gen.random(size)

    def _deliver(self, stamp: float) -> Scan:
        spec, n = self.spec, self.spec.rays
        measured = np.empty(n)
        kernels.scan_measure(
            self._true,
            self._draws(self.revolution),
            float(spec.noise_std),
            float(spec.noise_fraction),
            float(spec.resolution),
            float(spec.dropout),
            float(spec.range_min),
            float(spec.range_max),
            measured,
        )
        scan = Scan(
            stamp=stamp,
            angle_min=0.0,
            angle_increment=spec.angle_increment,
            ranges=measured,
            range_min=spec.range_min,
            range_max=spec.range_max,
            time_increment=self.time_increment,
            scan_time=self.period,
            frame=spec.frame,
            mount=self.mount,
        )
        self._true.fill(math.inf)
        self.last = scan
        self.scans += 1
        return scan
