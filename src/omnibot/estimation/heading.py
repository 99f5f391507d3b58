"""Heading from the gyro, with its bias and scale error estimated against the wheel encoders.

Seed 002 integrates the gyro, theta = theta + d_theta (its equation (1)). A MEMS gyro (MPU6050) has a
turn-on bias of about 0.01 rad/s (0.6 degree/s: 36 degrees a minute), a bias that wanders, and a
scale error of about 1 %, so the sum drifts. The wheels measure rotation too: right in the long run
while they roll without slipping, noisy in the short run (counts, roller wobble), and wrong for good
after a slip. :class:`HeadingFilter` is a small extended Kalman filter over

    x = (theta, bias, scale, offset)

    predict   theta += (d_psi - bias dt) / (1 + scale)        d_psi: the gyro's heading increment
              offset  random walk, faster the harder and faster the wheels work (acceleration a;
                      slip grows faster than the force as it nears the grip limit; speed v: fast
                      wheels creep in rotation):
                      q = (ref_drift^2 + (slip_per_accel2 a^2)^2 + (creep_per_speed2 v^2)^2) dt
    correct   z = theta_ref (the encoders' heading) = theta + offset + noise

The offset is the encoders' accumulated slip error. It barely moves while the robot drives quietly
(straight at a steady speed, turning steadily, standing), so there the difference between gyro and
wheels is bias plus scale times the rate: the bias is learned at standstill and while driving
straight, the scale once the robot turns (a spin in place is the cleanest, see the navigator's
gyro calibration). Under hard acceleration or cornering the offset may move, so the wheels' rotation
counts for little then, and nothing at all while a slip is seen: a slip check compares the encoders'
rotation with the gyro's over a short window (plus any slip flag from elsewhere: the wheel-fit
residual, the tracking wheels), and while it fires the reference follows the filter (no
information), so a slip never enters the heading. At standstill the rotation is known to be zero:
the gyro's rate is its bias, measured as the mean rate over the standstill so far (the heading's
quantisation and the gyro's noise average out over its length). A saturated gyro sample is the
least the body turned: it is replaced by the encoders' rotation only where they are trusted and
say more, else kept (the heading's variance grown by what the clip may hide).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from omnibot.robot import GyroSpec


@dataclass(frozen=True)
class HeadingFilterConfig:
    """Noise model and slip check of :class:`HeadingFilter` (defaults: an MPU6050 and the presets)."""

    angle_random_walk: float = 8.7e-5
    """Gyro noise density, rad/s/sqrt(Hz) (= rad/sqrt(s) of heading random walk)."""
    bias_walk: float = 2e-5
    """Bias random walk, rad/s/sqrt(s)."""
    bias_std: float = 0.01
    """Turn-on bias spread, rad/s (initial uncertainty)."""
    scale_std: float = 0.01
    """Scale-factor error spread (initial uncertainty)."""
    scale_walk: float = 1e-5
    """Scale-factor random walk, 1/sqrt(s) (temperature)."""
    ref_std: float = 0.004
    """Encoder heading noise, rad: bounded (roller wobble), correlated over ``ref_time``."""
    ref_time: float = 0.5
    """Correlation time of that noise, s."""
    ref_drift: float = 5e-4
    """Random walk of the encoders' slip offset while driving quietly, rad/sqrt(s)."""
    slip_per_accel2: float = 0.002
    """Extra offset random walk per (m/s^2)^2 of acceleration, rad/sqrt(s) (wheels under load slip)."""
    creep_per_speed2: float = 2.5e-4
    """Extra offset random walk per (m/s)^2 of body speed, rad/sqrt(s): fast wheels creep in rotation
    (omni3 at 4 m/s on carpet: 0.26 degree in 11 s without a skid to see)."""
    still_std: float = 2e-4
    """Heading quantisation step, rad (the TEL heading's 0.01 degree steps). Over a standstill of T s
    its errors telescope: the mean rate is off by two steps over T, not by one per sample."""
    slip_window: float = 0.1
    """Time constant of the leaky sum of gyro-encoder rotation differences, s."""
    slip_threshold: float = 3e-3
    """Leaky sum (rad) above which the wheels are taken to slip (plus the encoders' own resolution)."""
    slip_hold: float = 0.3
    """Seconds the encoder reference stays distrusted after the last slip."""
    gyro_range: float = math.inf
    """Gyro saturation, rad/s; samples near it are the least the body turned (see :meth:`HeadingFilter.update`)."""
    clip_excess: float = 0.05
    """How far past the range a clipped sample's true rate may be, as a fraction of it (heading variance)."""

    @classmethod
    def from_gyro(cls, spec: GyroSpec, **overrides: float) -> HeadingFilterConfig:
        """The noise model from a robot description's gyro section."""
        values: dict[str, float] = {
            "angle_random_walk": spec.noise_density,
            "bias_walk": max(spec.bias_walk, 1e-6),
            "bias_std": max(spec.bias_std, 1e-4),
            "scale_std": max(spec.scale_error_std, 1e-4),
            "gyro_range": spec.range,
        }
        values.update(overrides)
        return cls(**values)


@dataclass
class _Standstill:
    """A standstill so far: the filter's state at its start, the gyro's turn and time since, and the
    process noise added over it."""

    x: np.ndarray
    P: np.ndarray
    turned: float = 0.0
    time: float = 0.0
    noise: np.ndarray = field(default_factory=lambda: np.zeros((4, 4)))


class HeadingFilter:
    """Kalman filter over (heading, gyro bias, gyro scale error, encoder offset); see the module docstring."""

    def __init__(self, config: HeadingFilterConfig | None = None, theta: float = 0.0) -> None:
        self.config = c = config or HeadingFilterConfig()
        self.x = np.array([theta, 0.0, 0.0, 0.0])
        """State: heading (rad), bias (rad/s), scale error (fraction), encoder offset (rad)."""
        self.P = np.diag([1e-8, c.bias_std**2, c.scale_std**2, 1e-8])
        self._ref = theta
        self._mismatch = 0.0
        self._distrust = 0.0
        self._skid = 0.0
        self._stand: _Standstill | None = None
        self.slipping = False
        """The last update did not trust the encoders (slip seen, or held after one)."""

    @property
    def theta(self) -> float:
        """Estimated heading, rad."""
        return float(self.x[0])

    @property
    def bias(self) -> float:
        """Estimated gyro bias, rad/s."""
        return float(self.x[1])

    @property
    def scale(self) -> float:
        """Estimated gyro scale error (a fraction: 0.01 reads 1 % high)."""
        return float(self.x[2])

    def calibrated(self, bias: float, scale: float, bias_std: float, scale_std: float) -> None:
        """Take a batch calibration of the gyro (bias rad/s, scale error) with its uncertainty."""
        self.x[1], self.x[2] = bias, scale
        for i in (1, 2):
            self.P[i, :] = 0.0
            self.P[:, i] = 0.0
        self.P[1, 1], self.P[2, 2] = bias_std**2, scale_std**2
        self._stand = None  # a standstill's mean starts again from the calibration

    def reset_heading(self, theta: float) -> None:
        """Set the heading (keeping what was learned about the gyro)."""
        self.x[0] = theta
        self.x[3] = 0.0
        self._ref = theta
        for i in (0, 3):
            self.P[i, :] = 0.0
            self.P[:, i] = 0.0
            self.P[i, i] = 1e-8
        self._stand = None

    def update(
        self,
        dt: float,
        d_psi: float,
        d_ref: float | None,
        *,
        standstill: bool = False,
        slip: bool = False,
        accel: float = 0.0,
        speed: float = 0.0,
        ref_resolution: float = 0.0,
    ) -> float:
        """Fold in one interval; returns the heading increment (rad).

        ``d_psi`` is the gyro's heading increment, ``d_ref`` the encoders' rotation (None: no
        encoders), ``standstill`` that no wheel turned for a while, ``slip`` an outside slip flag,
        ``accel`` how hard the wheels work (m/s^2, rotation included), ``speed`` how fast the body goes
        (m/s), ``ref_resolution`` the
        encoders' rotation per count (widens the slip check).
        """
        c = self.config
        before = float(self.x[0])
        if dt <= 0:
            return 0.0
        theta, bias, scale, _ = (float(v) for v in self.x)
        saturated = abs(d_psi) > 0.97 * c.gyro_range * dt
        clip_var = 0.0
        if saturated:
            d_psi, clip_var = self._clipped(dt, d_psi, d_ref, slip, bias, scale)
        k = 1.0 + scale
        inc = 0.0 if standstill else (d_psi - bias * dt) / k  # standing: the body does not turn
        F = np.eye(4)
        if not standstill:
            F[0, 1], F[0, 2] = -dt / k, -inc / k
        self.x[0] = theta + inc
        drift = (
            c.ref_drift**2
            + (c.slip_per_accel2 * accel * accel) ** 2
            + (c.creep_per_speed2 * speed * speed) ** 2
        )
        Q = np.diag(
            [c.angle_random_walk**2 * dt + clip_var, c.bias_walk**2 * dt, c.scale_walk**2 * dt, drift * dt]
        )
        self.P = F @ self.P @ F.T + Q

        trusted = d_ref is not None and self._trusts(dt, d_ref - inc, slip, saturated, ref_resolution)
        self.slipping = d_ref is not None and not trusted

        if standstill:
            self._stand_update(dt, d_psi, Q)
        elif trusted:
            assert d_ref is not None
            self._ref += d_ref
            r = c.ref_std**2 * max(1.0, c.ref_time / dt)
            self._z_update(self._ref, r)
        else:
            self._ref += float(self.x[0]) - theta  # follow the filter: no information
        self._stand = self._stand if standstill else None
        return float(self.x[0]) - before

    def _stand_update(self, dt: float, d_psi: float, q: np.ndarray) -> None:
        """The body does not turn, so the gyro's rate is its bias: the state before the standstill,
        predicted over it, corrected once by the gyro's mean rate since it began. (One update per
        sample, each taking the heading's quantisation as new white noise, would leave the bias as
        uncertain as a single sample says, and the wheels' first creep would then move it.)"""
        c = self.config
        if self._stand is None:  # its start: the state before this interval (standing, P grew by q)
            self._stand = _Standstill(self.x.copy(), self.P - q)
        s = self._stand
        s.turned += d_psi
        s.time += dt
        s.noise += q
        self.x, self.P = s.x.copy(), s.P + s.noise
        r = c.angle_random_walk**2 / s.time + c.still_std**2 / (6.0 * s.time**2)
        self._bias_update(s.turned / s.time, r)

    def _clipped(
        self, dt: float, d_psi: float, d_ref: float | None, slip: bool, bias: float, scale: float
    ) -> tuple[float, float]:
        """A clipped gyro reading ``d_psi`` and the variance its clipping adds. It is the least the body
        turned: the encoders' rotation replaces it (no variance added) only where they are trusted
        and say more, in the same direction (a body spinning past the range usually has a wheel
        skidding, and skidding wheels read less)."""
        c = self.config
        bridged = None if d_ref is None else d_ref * (1.0 + scale) + bias * dt
        held = slip or self._skid > 0.0
        if bridged is not None and not held and bridged * d_psi > 0 and abs(bridged) > abs(d_psi):
            return bridged, 0.0
        return d_psi, (c.clip_excess * c.gyro_range * dt) ** 2

    def _trusts(self, dt: float, gap: float, slip: bool, saturated: bool, ref_resolution: float) -> bool:
        """Whether the encoders' rotation is trusted this interval: not while their ``gap`` to the
        gyro's, summed over the slip window, exceeds the slip threshold (widened by three counts of
        ``ref_resolution``), nor for :attr:`~HeadingFilterConfig.slip_hold` s after such a skid, an
        outside ``slip`` flag or a ``saturated`` gyro."""
        c = self.config
        decay = math.exp(-dt / c.slip_window)
        self._mismatch = self._mismatch * decay + gap
        limit = c.slip_threshold + 3.0 * ref_resolution
        skid = slip or abs(self._mismatch) > limit
        self._skid = c.slip_hold if skid else max(0.0, self._skid - dt)  # a clip alone is no skid
        if skid or saturated:
            self._distrust = c.slip_hold
            self._mismatch = 0.0
        else:
            self._distrust = max(0.0, self._distrust - dt)
        return self._distrust <= 0.0

    def _z_update(self, z: float, r: float) -> None:
        P = self.P
        H = np.array([1.0, 0.0, 0.0, 1.0])
        PH = P @ H
        K = PH / (H @ PH + r)
        self.x = self.x + K * (z - self.x[0] - self.x[3])
        self.P = P - np.outer(K, PH)

    def _bias_update(self, rate: float, r: float) -> None:
        P = self.P
        K = P[:, 1] / (P[1, 1] + r)
        self.x = self.x + K * (rate - self.x[1])
        self.P = P - np.outer(K, P[1, :])
