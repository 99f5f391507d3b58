"""Simulated sensors: motor encoders, passive tracking wheels, a yaw gyro and ultrasonic sonars.

Each sensor takes its spec from the robot description and a ``numpy.random.Generator``; the same
seed gives the same readings. The sensors know nothing of the physics: the simulator feeds them the
true wheel angles, body twist and pose, and they return what the hardware would report.

Counters are quantised with ``floor`` like a real counter (a count happens when an edge is
crossed), with a 1e-9 count allowance so that exactly one revolution gives exactly
``counts_per_rev`` despite rounding in 2 pi.

Cost per simulator step: the gyro and tracking wheels keep their state in float arrays that the
simulator's compiled step updates (:func:`omnibot.sim.kernels.robot_step`), taking their normal
draws from blocks generated ahead (:class:`NormalDraws`, the same numbers as drawing one at a time);
motor encoders given a ``source`` count only when read; a sonar ping is one compiled pass over the
world's edges (:func:`omnibot.sim.kernels.cone_distance`).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from omnibot.motion import Pose2D
from omnibot.robot import GyroSpec, SonarSpec, TrackingWheelSpec
from omnibot.sim import jit
from omnibot.sim.geometry import cone_range
from omnibot.sim.kernels import layout
from omnibot.sim.world import World

IntArray = NDArray[np.int64]
FloatArray = NDArray[np.float64]
_EDGE_EPS = 1e-9


def _count(revolutions: FloatArray, cpr: FloatArray) -> IntArray:
    return np.floor(revolutions * cpr + _EDGE_EPS).astype(np.int64)


class NormalBlock:
    """Standard normal draws from a Generator, generated a block at a time.

    Calling it gives the same sequence as calling ``rng.standard_normal()`` each time (the
    Generator's draws do not depend on how many are asked for at once), but costs a list lookup.
    The first block is drawn at the first call, so draws made from ``rng`` before then come first;
    the Generator must not be used for anything else afterwards.
    """

    def __init__(self, rng: np.random.Generator, block: int = 1024) -> None:
        self._rng = rng
        self._block = block
        self._values: list[float] = []
        self._next = 0

    def __call__(self) -> float:
        """The next standard normal draw."""
        k = self._next
        if k >= len(self._values):
            self._values = self._rng.standard_normal(self._block).tolist()
            k = 0
        self._next = k + 1
        return self._values[k]


class MotorEncoders:
    """Quadrature encoders on the driven wheels: counts per wheel revolution, floor-quantised.

    ``miss_probability`` is the chance that any one edge is not counted (a noisy line or a slow
    interrupt); missed counts are lost for good, so counts stay monotone while the wheel turns one
    way. Counts start at 0 for the angles given at construction (power-on).

    With a ``source`` (a callable returning the true wheel angles) the encoders count when
    :attr:`counts` is read instead of at every :meth:`update`: the counts are the same, and the
    missed edges are drawn for all the edges since the last read at once (the same distribution
    while a wheel turns one way).
    """

    def __init__(
        self,
        counts_per_rev: Sequence[int],
        rng: np.random.Generator,
        *,
        miss_probability: float = 0.0,
        initial_angles: ArrayLike | None = None,
        source: Callable[[], ArrayLike] | None = None,
    ) -> None:
        if not 0.0 <= miss_probability <= 1.0:
            raise ValueError(f"miss_probability must be in [0, 1], got {miss_probability}")
        self._cpr = np.asarray(counts_per_rev, dtype=float)
        self._rng = rng
        self.miss_probability = miss_probability
        angles = np.zeros(len(self._cpr)) if initial_angles is None else np.asarray(initial_angles, float)
        self._edges = _count(angles / (2 * math.pi), self._cpr)
        self._origin = self._edges.copy()
        self._cpr_list: list[float] = self._cpr.tolist()
        self._origin_list: list[int] = self._origin.tolist()
        self._lost = np.zeros(len(self._cpr), dtype=np.int64)
        self._source = source

    def _feed(self, wheel_angles: ArrayLike) -> None:
        edges = _count(np.asarray(wheel_angles, dtype=float) / (2 * math.pi), self._cpr)
        if self.miss_probability > 0:
            delta = edges - self._edges
            missed = self._rng.binomial(np.abs(delta), self.miss_probability)
            self._lost += np.sign(delta) * missed
        self._edges = edges

    def update(self, wheel_angles: ArrayLike) -> IntArray:
        """Feed the true wheel angles (rad); return the counts."""
        self._feed(wheel_angles)
        return np.asarray(self._edges - self._origin - self._lost, dtype=np.int64)

    @property
    def counts(self) -> IntArray:
        """Cumulative counts per wheel since the start, less the edges the encoder missed."""
        if self._source is not None:
            self._feed(self._source())
        return np.asarray(self._edges - self._origin - self._lost, dtype=np.int64)

    def count_at(self, i: int, angle: float) -> int:
        """Encoder ``i``'s count with its wheel at ``angle`` rad (the true angle now): what
        :attr:`counts` would give for it, without counting the others (the firmware reads one
        encoder at a time). Only where no edge can be missed (``miss_probability`` 0), since those are
        drawn for every encoder at once; the same floating-point operations as :func:`_count`."""
        edges = math.floor(angle / (2 * math.pi) * self._cpr_list[i] + _EDGE_EPS)
        return edges - self._origin_list[i] - int(self._lost[i])


class NormalDraws:
    """Standard normal draws from a Generator kept in an array for a compiled sensor update, which
    takes them from index ``state[cursor]`` on and moves that index.

    :meth:`refill` keeps the draws not yet used and appends a block of new ones, so the sequence is
    the Generator's own (as :class:`NormalBlock`'s); the Generator must not be used for anything
    else once the first block is drawn.
    """

    def __init__(self, rng: np.random.Generator, block: int = 1024) -> None:
        self._rng = rng
        self._block = block
        self.values: FloatArray = np.zeros(0)
        """The draws; the sensor's state says which is next."""

    def refill(self, state: FloatArray, cursor: int, least: int) -> None:
        """Make sure at least ``least`` unused draws are there (``state[cursor]``: the next one)."""
        k = int(state[cursor])
        if len(self.values) - k < least:
            self.values = np.concatenate(
                (self.values[k:], self._rng.standard_normal(max(self._block, least)))
            )
            state[cursor] = 0.0


class TrackingWheels:
    """Passive measuring wheels: each rolls with the body velocity at its mount, along its direction.

    The rolled distance per step is ``u . (v + w x p) * dt * (1 + slip)`` with ``slip`` drawn from
    N(0, ``slip_std``) every step (a wheel that skids a little on the floor). The state is one
    float array (:attr:`state`, :data:`omnibot.sim.layout.T_HEADER` layout) that the simulator's
    compiled step updates.
    """

    def __init__(
        self, specs: Sequence[TrackingWheelSpec], rng: np.random.Generator, *, slip_std: float = 0.01
    ) -> None:
        self.specs = tuple(specs)
        self.normals = NormalDraws(rng)
        self.slip_std = slip_std
        self._pos = np.array([(s.x, s.y) for s in specs], dtype=float).reshape(-1, 2)
        self._dir = np.array([(math.cos(s.direction), math.sin(s.direction)) for s in specs]).reshape(-1, 2)
        self._circ = np.array([2 * math.pi * s.radius for s in specs], dtype=float)
        self._cpr = np.array([s.counts_per_rev for s in specs], dtype=float)
        self.state = np.zeros(layout.T_HEADER + layout.T_WHEEL * len(self.specs))
        self.state[layout.T_SLIP] = slip_std
        wheels = self.state[layout.T_HEADER :].reshape(-1, layout.T_WHEEL)
        wheels[:, 0:2], wheels[:, 2:4] = self._dir, self._pos
        self.refill()

    def refill(self) -> None:
        """Make sure the normal draws of the next two updates are there."""
        if self.specs and self.slip_std > 0:
            self.normals.refill(self.state, layout.T_NEXT, 2 * len(self.specs))

    @property
    def distance(self) -> FloatArray:
        """Distance each wheel has rolled (m), slip included."""
        return np.array(self.state[layout.T_HEADER + 4 :: layout.T_WHEEL], dtype=float)

    def velocities(self, twist: ArrayLike) -> FloatArray:
        """Rim speed of each wheel (m/s) for a body twist (vx, vy, w): u . (v + w x p)."""
        vx, vy, w = (float(c) for c in np.asarray(twist, dtype=float))
        return np.array(
            [
                (vx - w * py) * ux + (vy + w * px) * uy
                for (ux, uy), (px, py) in zip(self._dir, self._pos, strict=True)
            ]
        )

    def update(self, twist: Sequence[float], dt: float) -> IntArray:
        """Roll the wheels for ``dt`` seconds at the body twist (vx, vy, w); return the counts."""
        if self.specs:
            vx, vy, w = (float(c) for c in twist)
            jit.active.tracking_update(self.state, self.normals.values, vx, vy, w, float(dt))
            self.refill()
        return self.counts

    @property
    def counts(self) -> IntArray:
        """Cumulative counts per tracking wheel."""
        return _count(self.distance / self._circ, self._cpr)


class Gyro:
    """A MEMS yaw-rate gyro sampled at ``spec.rate_hz``.

    Each sample is the true rate averaged over the sample period, then::

        rate = (1 + scale_error) * true + bias + N(0, noise_density * sqrt(rate_hz))

    saturated at +-``range`` and quantised to ``resolution``. The turn-on bias is drawn from
    N(0, bias_std) and the scale error from N(0, scale_error_std) at construction; the bias walks by
    N(0, bias_walk * sqrt(period)) per sample. With this convention the mean of one second of
    samples at rest has a standard deviation of ``noise_density`` (the angle random walk).

    The state is one float array (:attr:`state`, the ``G_`` columns of :mod:`omnibot.sim.kernels`)
    that the simulator's compiled step updates; :meth:`update` and :meth:`measure` run the same
    compiled code.
    """

    def __init__(self, spec: GyroSpec, rng: np.random.Generator) -> None:
        self.spec = spec
        self.period = 1.0 / spec.rate_hz
        g = self.state = np.zeros(layout.G_COLUMNS)
        g[layout.G_BIAS] = float(rng.normal(0.0, spec.bias_std)) if spec.bias_std > 0 else 0.0
        g[layout.G_SCALE] = float(rng.normal(0.0, spec.scale_error_std)) if spec.scale_error_std > 0 else 0.0
        self.normals = NormalDraws(rng)  # after the turn-on draws: the same stream as before
        g[layout.G_SIGMA] = spec.noise_density * math.sqrt(spec.rate_hz)
        g[layout.G_WALK] = spec.bias_walk * math.sqrt(self.period)
        g[layout.G_DUE] = self.period - 1e-12
        g[layout.G_PERIOD] = self.period
        g[layout.G_RANGE], g[layout.G_RESOLUTION] = float(spec.range), float(spec.resolution)

    def refill(self, dt: float = 0.0) -> None:
        """Make sure the normal draws of two updates of ``dt`` are there."""
        self.normals.refill(self.state, layout.G_NEXT, 4 * (int(dt / self.period) + 2))

    @property
    def bias(self) -> float:
        """The bias now, rad/s (drawn at turn-on, then walking)."""
        return float(self.state[layout.G_BIAS])

    @property
    def scale_error(self) -> float:
        """The scale factor's error (drawn at turn-on)."""
        return float(self.state[layout.G_SCALE])

    @property
    def rate(self) -> float:
        """Latest sample, rad/s (0 before the first)."""
        return float(self.state[layout.G_RATE])

    @property
    def angle(self) -> float:
        """Sum of samples times the period: the heading a firmware integrating this gyro would have."""
        return float(self.state[layout.G_ANGLE])

    @property
    def samples(self) -> int:
        """Samples taken."""
        return int(self.state[layout.G_SAMPLES])

    def update(self, dt: float, true_rate: float) -> bool:
        """Advance ``dt`` seconds at ``true_rate``; True if at least one new sample was taken."""
        self.refill(dt)
        return bool(jit.active.gyro_update(self.state, self.normals.values, float(dt), float(true_rate)))

    def measure(self, true_rate: float) -> float:
        """Take one sample of a (period-averaged) true rate; returns it and stores it in :attr:`rate`."""
        self.refill()
        return float(jit.active.gyro_measure(self.state, self.normals.values, float(true_rate)))


class Sonar:
    """An ultrasonic range finder (HC-SR04 by default) looking into a world.

    A measurement is the distance to the nearest wall or obstacle point inside the cone (see
    :meth:`World.cone_range`), plus N(0, noise_std), clamped below at ``min_range``. It is None (no
    echo) when nothing is within ``max_range`` or, with ``miss_probability``, at random. The echo's
    flight time is not simulated: a ping answers at once.

    :meth:`ping` respects the sensor's cycle: a ping less than ``period_min`` after the previous
    measurement does not measure again and returns the previous result (None if it had no echo).
    """

    def __init__(self, spec: SonarSpec, rng: np.random.Generator) -> None:
        self.spec = spec
        self._rng = rng
        self.last: float | None = None
        self.last_time: float | None = None

    def pose_in_world(self, pose: Sequence[float]) -> Pose2D:
        """The sensor's own pose for a robot pose (x, y, theta)."""
        x, y, th = (float(c) for c in pose[:3])
        c, s = math.cos(th), math.sin(th)
        return Pose2D(
            x + c * self.spec.x - s * self.spec.y, y + s * self.spec.x + c * self.spec.y, th + self.spec.angle
        )

    def measure(self, pose: Sequence[float], world: World, others: FloatArray | None = None) -> float | None:
        """One measurement now, ignoring the cycle time; ``others`` are edges ``(K, 4)`` of other
        bodies in the world frame (a fleet's other robots), seen as the world's walls are."""
        spec = self.spec
        miss, noise = self._rng.random(), self._rng.normal(0.0, 1.0)  # drawn every time: stable streams
        sp = self.pose_in_world(pose)
        true = world.cone_range(sp.x, sp.y, sp.theta, spec.cone, spec.max_range)
        if others is not None and len(others):
            true = min(true, cone_range(others, sp.x, sp.y, sp.theta, spec.cone, spec.max_range))
        if math.isinf(true) or miss < spec.miss_probability:
            return None
        value = max(true + spec.noise_std * float(noise), spec.min_range)
        return value if value <= spec.max_range else None

    def ping(
        self, now: float, pose: Sequence[float], world: World, others: FloatArray | None = None
    ) -> float | None:
        """Measure at time ``now`` (s) unless the last measurement is younger than ``period_min``."""
        if self.last_time is not None and now - self.last_time < self.spec.period_min - 1e-9:
            return self.last
        self.last = self.measure(pose, world, others)
        self.last_time = now
        return self.last
