"""A simulated spinning 2D laser scanner (an RPLIDAR by default): rays cast as the revolution turns.

The robot's compiled step records its true pose every few steps (every 5 ms) in a log of its own
(:func:`~omnibot.sim.kernels.pose_log`), read through a :class:`PoseLog` (a fleet's reads every
robot's log, side by side), and the scanner casts
the rays that have come due when asked (:meth:`LaserScanner.flush`), each from the pose its robot
had at that ray's own time and against the other bodies of the log where they were at that time
(linear between the recorded steps): a robot that moves or turns during a revolution gets a
distorted scan, as a real spinning scanner's is, and sees the others moving. Nothing is simulated
twice: the poses are those the physics already stepped through.

Revolution ``k`` starts at simulated time ``k / rate_hz``; its ray ``i`` is measured
``i * time_increment`` later (``period / rays``; 0 with ``motion_distortion`` off: every ray at the
revolution's start) and points at ``i * angle_increment`` in the scanner frame, where the increment
is negative for a clockwise scanner (the RPLIDAR's way): the scan keeps the order the rays were
measured in and gives angles counter-clockwise positive, as :class:`omnibot.scan.Scan` requires.
A revolution is delivered as a :class:`~omnibot.scan.Scan` once its last ray's time has passed.

Each range is the true distance to the nearest wall, obstacle or other body plus
N(0, noise_std + noise_fraction * distance), quantised to ``resolution``; ``inf`` for a dropout or
a return outside [range_min, range_max]. The noise comes from the scanner's own random stream (a
PCG64 of its seed and key) in a fixed layout: revolutions ``8b`` to ``8b + 7`` (batch ``b`` of
DRAW_BATCH) take the block of ``DRAW_BATCH * BLOCK_PER_RAY * rays`` outputs (3 a ray) that starts at
output ``b`` times that, first their uniform draws (``Generator.random``, ``rays`` a revolution:
the dropouts), then their standard normals (``Generator.standard_normal``, numpy's ziggurat,
``rays`` a revolution), which take about 1.02 outputs each (2,940 for 2,880; the block leaves them
twice as many). So a revolution's ranges are the same whenever the scanner was switched on and
however often it was flushed, and no other sensor's stream changes.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Protocol

import numpy as np
from numpy.typing import NDArray

from omnibot.errors import SimulationError
from omnibot.motion import Pose2D
from omnibot.robot import ScannerSpec
from omnibot.scan import Scan
from omnibot.sim import jit
from omnibot.sim.kernels import layout, ray_table
from omnibot.sim.kernels.scan import (
    P_DROPOUT,
    P_DT,
    P_INNER,
    P_MOUNT_X,
    P_MOUNT_Y,
    P_NOISE_FRACTION,
    P_NOISE_STD,
    P_RANGE_MAX,
    P_RANGE_MIN,
    P_REACH,
    P_RESOLUTION,
    P_T0,
    SCAN_BINS,
    SCAN_PARAMS,
)

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

_EPS = 1e-9
_NO_VERTICES = np.zeros((0, 2))
_NO_BODIES = np.zeros(1, dtype=np.int64)
_NO_RAYS = np.zeros(0)
_NO_INDEX = (np.zeros(SCAN_BINS + 1, dtype=np.int64), np.zeros(0, dtype=np.int64), np.zeros(0))
DRAW_BATCH = 8
"""Revolutions whose noise is drawn together: revolutions ``8b`` to ``8b + 7`` (batch ``b``)."""
BLOCK_PER_RAY = 3
"""Outputs of the scanner's stream a ray's draws have in its batch's block: its uniform, and room
for its normal (one output, or a few on a rejection)."""
INDEX_SLACK = 0.25
"""m: room the scanner's edge index leaves around the origins it was made for (see _index_for)."""


SCAN_POSE_PERIOD = 0.005
"""s: how often the compiled step records the pose while a scanner is on (every step if dt is
longer). The rays' poses are linear between records: off by at most v w T^2 / 8 on a curve (31 um
at 1 m/s and 10 rad/s), far below any scanner's noise (10 mm at 1 m)."""
LOG_SPAN = 0.25
"""s: the least time a pose log holds (:func:`pose_log_rows`); a scanner's log holds two of its
revolutions if that is more."""


def pose_log_rows(period: float, stride: float) -> int:
    """Rows a pose log recorded every ``stride`` s needs for a scanner whose revolution lasts
    ``period`` s (0: none; the log then serves the other scanners of a fleet): LOG_SPAN or two
    revolutions, and a few strides to spare."""
    return math.ceil(max(LOG_SPAN, 2.0 * period) / stride - _EPS) + 3


class PoseSource(Protocol):
    """A body whose compiled step records its pose (:func:`~omnibot.sim.kernels.pose_log`)."""

    def pose_log(self) -> tuple[FloatArray, IntArray]:
        """Its log's rows (capacity, 3) and the int state whose ``I_LOG_`` columns describe them."""
        ...


class PoseLog:
    """Poses of ``bodies`` recorded every ``dt`` seconds from ``start`` by their compiled steps, each
    in its own log: row j (time ``start + j * dt``) is x, y, theta of body 0, then of body 1...
    (:meth:`array`). The logs start together (each body's ``_pose_log_start``) and are trimmed
    together (:meth:`trim`); ``start_us`` is ``start`` in whole us, for scheduling."""

    def __init__(self, bodies: Sequence[PoseSource], dt: float, start_us: int = 0) -> None:
        self.bodies = list(bodies)
        self.width = 3 * len(self.bodies)
        self.dt = dt
        self.stride_us = round(dt * 1e6)
        self.start = start_us / 1e6
        self.start_us = start_us
        self.capacity = min((len(b.pose_log()[0]) for b in self.bodies), default=0)
        self._joined = np.zeros((0, self.width))
        self._joined_key = (-1, -1)

    def array(self) -> FloatArray:
        """The rows as an (H, 3 bodies) array: a view of the body's log when there is one body, else
        the bodies' logs side by side (made once per record: the scanners of a fleet flushed
        together share it)."""
        rows, si = self.bodies[0].pose_log()
        n = int(si[layout.I_LOG_N])
        if n > self.capacity:
            raise SimulationError(
                f"the scanners' pose log overflowed ({n} rows in {self.capacity}): a flush came too late"
            )
        if len(self.bodies) == 1:
            return rows[:n]
        key = (n, int(si[layout.I_LOG_NEXT]))
        if key != self._joined_key:
            self._joined = np.concatenate([b.pose_log()[0][:n] for b in self.bodies], axis=1)
            self._joined_key = key
        return self._joined

    def trim(self, t: float) -> None:
        """Forget the rows older than the last one at or before time ``t`` (s)."""
        logs = [b.pose_log() for b in self.bodies]
        n = int(logs[0][1][layout.I_LOG_N])
        drop = math.floor((t - self.start) / self.dt + _EPS)
        drop = min(max(drop, 0), n - 1)
        if drop > 0:
            for rows, si in logs:
                rows[: n - drop] = rows[drop:n]
                si[layout.I_LOG_N] = n - drop
            self.start += drop * self.dt
            self.start_us += drop * self.stride_us

    def flush_at(self, due_us: int) -> int:
        """When (us) to flush for a revolution due at ``due_us``: the first record at or after it, or
        the one that fills the log if that comes first."""
        stride = self.stride_us
        tick = self.start_us + -(-(due_us - self.start_us) // stride) * stride
        return min(tick, self.start_us + (self.capacity - 1) * stride)


class LaserScanner:
    """One robot's scanner: its :class:`~omnibot.robot.sensors.ScannerSpec`, and the seed and
    stream key of its random numbers."""

    def __init__(self, spec: ScannerSpec, seed: int, key: int) -> None:
        self.spec = spec
        n = spec.rays
        self.period = spec.period
        self.time_increment = self.period / n if spec.motion_distortion else 0.0
        self.mount = Pose2D(spec.x, spec.y, spec.yaw)
        self.angle_increment = spec.angle_increment
        """Angle between consecutive rays, rad (negative: clockwise)."""
        self.angles: FloatArray = np.arange(n, dtype=np.float64) * self.angle_increment
        """Direction of every ray in the scanner frame, rad."""
        self._offsets = np.arange(n, dtype=np.float64) * self.time_increment
        self._rays = ray_table.py_func(self._offsets, self.angles + spec.yaw)
        """Each ray's time in the revolution and direction in the robot's base frame, with its cos and sin."""
        self._bitgen = np.random.PCG64(np.random.SeedSequence(seed, spawn_key=(key,)))
        self._gen = np.random.Generator(self._bitgen)
        self._stream_start = self._bitgen.state
        """The stream's state at its start, from which each batch's block is reached."""
        stretch = 1.0 + 6.0 * spec.noise_fraction
        self._cast_range = spec.range_max * stretch + 6.0 * spec.noise_std + spec.resolution
        self._true = np.full(n, math.inf)
        self._mount_reach = math.hypot(spec.x, spec.y)
        self._index: tuple[IntArray, IntArray, FloatArray] = _NO_INDEX
        self._index_segments: FloatArray | None = None
        self._params = np.zeros(SCAN_PARAMS)
        """:func:`~omnibot.sim.kernels.scan_revolution`'s parameters (its ``P_`` columns)."""
        self._params[[P_MOUNT_X, P_MOUNT_Y, P_REACH, P_INNER]] = spec.x, spec.y, self._cast_range, -1.0
        self._params[P_NOISE_STD : P_RANGE_MAX + 1] = (
            spec.noise_std, spec.noise_fraction, spec.resolution, spec.dropout, spec.range_min, spec.range_max,
        )  # fmt: skip
        self._uniforms = np.empty((DRAW_BATCH, n))
        self._normals = np.empty((DRAW_BATCH, n))
        """Uniform and normal draws of batch _batch's revolutions: one per row."""
        self._rows = list(zip(self._normals, self._uniforms, strict=True))
        self._batch = -1
        self._template = Scan(
            stamp=0.0,
            angle_min=0.0,
            angle_increment=self.angle_increment,
            ranges=self._true,
            range_min=spec.range_min,
            range_max=spec.range_max,
            time_increment=self.time_increment,
            scan_time=self.period,
            frame=spec.frame,
            mount=self.mount,
        )
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

    def start(self, t: float) -> None:
        """Start measuring at simulated time ``t`` (s): the first revolution is the first that starts
        at or after ``t``; poses are needed from :attr:`needs_from` on."""
        self.active = True
        self.revolution = math.ceil(t / self.period - _EPS)
        self._next_ray = 0
        self.due = self.revolution * self.period + self.period

    def stop(self) -> None:
        """Stop measuring; the revolution under way is dropped."""
        self.active = False
        self.due = math.inf

    @property
    def needs_from(self) -> float:
        """Time (s) of the next ray to cast: the poses before it are no longer needed."""
        nxt = self._next_ray
        return self.revolution * self.period + (self._offsets[nxt] if nxt < self.spec.rays else self.period)

    # ------------------------------------------------------------------ measuring

    def flush(
        self,
        t: float,
        segments: FloatArray,
        poses: PoseLog,
        own: int = 0,
        bodies: tuple[FloatArray, IntArray] | None = None,
    ) -> list[Scan]:
        """Cast every ray due by simulated time ``t`` (s); returns the revolutions completed.

        The rays meet the world's edges ``segments`` (K, 4) and the other bodies of ``poses``
        (body ``own`` is the scanner's robot): ``bodies`` gives every body's outline in its own
        frame, packed (all vertices (V, 2), offsets (bodies + 1,)); None: the log holds only the robot.
        A revolution is cast, measured and delivered in one compiled call
        (:func:`~omnibot.sim.kernels.scan_revolution`) when its rays come due together (the usual flush).
        """
        if not self.active:
            return []
        body_v, body_off = bodies if bodies is not None else (_NO_VERTICES, _NO_BODIES)
        hist = poses.array()
        params = self._params
        params[P_T0], params[P_DT] = poses.start, poses.dt
        if segments is not self._index_segments:
            params[P_INNER] = -1.0  # the index is of other edges
        done: list[Scan] = []
        n = self.spec.rays
        while True:
            stamp = self.revolution * self.period
            end = stamp + self.period
            whole = t >= end - _EPS  # the usual call: its end is the due time
            last = n if whole else int(np.searchsorted(self._offsets, t - stamp + _EPS, side="right"))
            measured = np.empty(n) if whole else _NO_RAYS
            normals, uniforms = self._draws(self.revolution) if whole else (_NO_RAYS, _NO_RAYS)
            first, cast = self._next_ray, last > self._next_ray
            while cast and not jit.active.scan_revolution(
                stamp, first, last, self._rays, hist, own, params, segments, *self._index,
                body_v, body_off, self._true, normals, uniforms, measured,
            ):  # fmt: skip
                self._index_for(segments, hist, own)
            self._next_ray = last
            if not whole:
                break
            if not cast:  # every ray was cast by earlier flushes: measured here
                self._measure(normals, uniforms, measured)
            done.append(self._deliver(stamp, measured))
            self.revolution += 1
            self._next_ray = 0
            if t < end + self.period - _EPS:
                break  # the next revolution's rays due by now are cast with the rest of it
        self.due = self.revolution * self.period + self.period
        return done

    def _index_for(self, segments: FloatArray, hist: FloatArray, own: int) -> None:
        """A new edge index by direction for origins anywhere the scanner was in ``hist``, with
        INDEX_SLACK to spare (:func:`~omnibot.sim.kernels.scan_index_around`; ``scan_revolution``
        keeps it while it holds every origin and the edges are the same: a robot driving at 1 m/s
        needs a new one every few revolutions and a standing one never)."""
        self._index = jit.active.scan_index_around(
            segments, hist, own, self._mount_reach, INDEX_SLACK, self._cast_range, self._params
        )
        self._index_segments = segments

    def _draws(self, revolution: int) -> tuple[FloatArray, FloatArray]:
        """The normal and the uniform draws of ``revolution`` (what
        :func:`~omnibot.sim.kernels.scan_measure` takes): rows of its batch's, drawn from the
        batch's block of the stream (the module's docstring gives the layout)."""
        batch, row = divmod(revolution, DRAW_BATCH)
        if batch != self._batch:
            bits = self._bitgen
            bits.state = self._stream_start
            bits.advance(batch * DRAW_BATCH * BLOCK_PER_RAY * self.spec.rays)
            self._gen.random(out=self._uniforms)
            self._gen.standard_normal(out=self._normals)
            self._batch = batch
        return self._rows[row]

    def _measure(self, normals: FloatArray, uniforms: FloatArray, measured: FloatArray) -> None:
        """The revolution's true ranges measured into ``measured`` (:func:`~omnibot.sim.kernels.scan_measure`)."""
        p = self._params
        jit.active.scan_measure(
            self._true, normals, uniforms, p[P_NOISE_STD], p[P_NOISE_FRACTION], p[P_RESOLUTION], p[P_DROPOUT],
            p[P_RANGE_MIN], p[P_RANGE_MAX], measured,
        )  # fmt: skip

    def _deliver(self, stamp: float, measured: FloatArray) -> Scan:
        """The revolution that began at ``stamp``, measured, as a :class:`~omnibot.scan.Scan` (the
        scanner's own checked once: :meth:`Scan.but <omnibot.scan.Scan.but>`)."""
        scan = self._template.but(stamp, measured)  # _true is cast again, every ray, before it is read
        self.last = scan
        self.scans += 1
        return scan
