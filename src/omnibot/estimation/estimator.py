"""The robot's pose from its telemetry: encoders, tracking wheels and gyro fused, on the host.

One :class:`PoseEstimator` update per telemetry sample (TEL at 50-100 Hz, docs/navigation.md says
why on the host)::

    sample (controller time, motor counts, tracking counts, gyro heading)
      motor counts -> least-squares forward kinematics -> (dx, dy, d_theta)_wheels + residual
      gyro heading -> HeadingFilter (bias, scale; encoders as reference, slip check) -> d_theta
      translation: tracking wheels with the w x p term removed (TrackingOdometry), else the wheels'
      pose <- arc (compose_arc); velocity <- displacement / dt, low-passed

Estimators are small strategies registered by name (:data:`~omnibot.estimation.registry.ESTIMATORS`,
:func:`~omnibot.estimation.registry.make_estimator`), so a benchmark can run several on the same
telemetry. Inputs are plain: anything with the attributes
of :class:`SensorSample` (the client's ``Telemetry`` event has them).
"""

from __future__ import annotations

import math
from collections import deque
from typing import Protocol

import numpy as np

from omnibot.errors import ConfigError
from omnibot.estimation.creep import SlipParameters
from omnibot.estimation.heading import HeadingFilter, HeadingFilterConfig
from omnibot.estimation.odometry import COUNT_MODULUS, compose_arc, count_delta
from omnibot.estimation.silence import GyroSilence
from omnibot.estimation.slip import SlipModel
from omnibot.estimation.tracking import TrackingGeometry
from omnibot.estimation.wheelslip import SKID_MARGIN, WheelSlipCheck
from omnibot.motion import Estimate, Pose2D
from omnibot.robot import RobotDescription
from omnibot.robot.kinematics import forward_matrix, world_to_body

STILL_TIME = 0.2
"""Seconds without a single encoder count after which the robot is taken to stand still. An
estimator starts standing still (as its first :class:`~omnibot.motion.Estimate` says): until a wheel
first turns, the gyro's rate is its bias, not a turn (its turn-on bias integrated over this window
would tilt the start heading, and with it a map started there)."""
VELOCITY_TAU = 0.03
"""Time constant of the velocity low-pass, s."""
ACCEL_SPAN = 0.1
"""s between the three poses of the second difference that measures how hard the wheels work (for
HeadingFilter: the harder, the less their rotation is worth); long enough that encoder counts do
not turn into noise. Angular acceleration counts at a 0.2 m lever."""
TRACK_SLIP_WINDOW = 0.1
"""Time constant of the leaky sum of tracking-wheel vs driven-wheel translation differences, s."""
TRACK_SLIP_GAP, TRACK_SLIP_FRACTION = 0.003, 0.05
"""That sum above this many metres plus this fraction of the distance travelled in the window: slip."""
ACCEL_TAU = 0.05
"""Time constant of the low-passed acceleration (the slip model's input, the velocity's lag), s."""


class SensorSample(Protocol):
    """One telemetry sample: what an estimator reads (None: the group was not sent)."""

    @property
    def controller_time(self) -> float:
        """The controller's clock at this sample, s."""

    @property
    def encoders(self) -> tuple[int, ...] | None:
        """Cumulative driven-wheel encoder counts, one per motor encoder."""

    @property
    def tracking(self) -> tuple[int, ...] | None:
        """Cumulative tracking-wheel encoder counts, one per tracking wheel."""

    @property
    def heading(self) -> float | None:
        """The gyro's integrated heading, rad."""


class Estimator(Protocol):
    """What the navigation loop needs of an estimator."""

    name: str
    estimate: Estimate
    alerts: list[str]
    """What the estimator found wrong with the robot's sensors, each once (e.g. a silent gyro); the
    runtime tells every front end and empties it."""

    @property
    def distance(self) -> float:
        """Path length driven so far, m."""

    def update(self, sample: SensorSample) -> Estimate:
        """Fold in one sample; the new estimate."""


def _every_wheel_counted(robot: RobotDescription) -> bool:
    """Whether every driven wheel has a motor encoder."""
    counted = {e.wheel for e in robot.encoders.motors}
    return all(w.name in counted for w in robot.wheels)


def _sources(robot: RobotDescription, translation: str, heading: str) -> tuple[str, str]:
    """:class:`PoseEstimator`'s translation and heading sources, ``auto`` resolved for ``robot``;
    ConfigError for an unknown one or one whose sensors the robot lacks."""
    if translation == "auto":
        translation = "tracking" if len(robot.encoders.tracking) >= 2 else "encoders"
    if heading == "auto":
        heading = "fused" if robot.gyro is not None else "encoders"
    if translation not in ("tracking", "encoders"):
        raise ConfigError(f"unknown translation source {translation!r}; expected tracking or encoders")
    if heading not in ("fused", "gyro", "encoders"):
        raise ConfigError(f"unknown heading source {heading!r}; expected fused, gyro, encoders or auto")
    if heading in ("fused", "gyro") and robot.gyro is None:
        raise ConfigError(f"robot {robot.name} has no gyro for heading '{heading}'")
    if (translation == "encoders" or heading == "encoders") and not _every_wheel_counted(robot):
        raise ConfigError(f"robot {robot.name} lacks an encoder on every driven wheel")
    return translation, heading


class PoseEstimator:
    """Dead reckoning with a choice of translation and heading sources.

    ``translation``: ``"tracking"`` (passive tracking wheels), ``"encoders"`` (driven-wheel encoders)
    or ``"auto"`` (tracking wheels when the robot has them). ``heading``: ``"fused"`` (gyro with bias
    and scale learned against the encoders), ``"gyro"`` (the raw gyro sum, seed 002's (1)) or
    ``"encoders"`` (the wheels' rotation only) or ``"auto"`` (fused when the robot has a gyro); a gyro whose heading stands still while the encoders
    turn the body (:mod:`omnibot.estimation.silence`: a controller without one sends 0) gives way to
    the encoders, with an alert. ``slip``: the floor's wheel slip
    (:mod:`omnibot.estimation.slip`, from ``omnibot calibrate``): the driven wheels' increments are
    scaled and their predicted creep taken out before the forward kinematics.
    """

    def __init__(
        self,
        robot: RobotDescription,
        *,
        translation: str = "auto",
        heading: str = "fused",
        start: Pose2D | None = None,
        name: str = "",
        filter_config: HeadingFilterConfig | None = None,
        slip: SlipParameters | None = None,
    ) -> None:
        translation, heading = _sources(robot, translation, heading)
        self.has_encoders = _every_wheel_counted(robot)
        self.name = name or f"{translation}+{heading}"
        self.robot_name = robot.name
        self.alerts: list[str] = []
        self.silence = GyroSilence()
        """Whether the gyro says nothing (then the heading comes from the encoders)."""
        self._still_theta = start.theta if start else 0.0
        self.translation = translation
        self.heading_source = heading
        self.tracking = (
            TrackingGeometry(robot.encoders.tracking, robot.name) if translation == "tracking" else None
        )
        self._init_wheel_odometry(robot, slip)
        config = filter_config
        if config is None and robot.gyro is not None:
            config = HeadingFilterConfig.from_gyro(robot.gyro)
        self.filter = HeadingFilter(config, theta=start.theta if start else 0.0)
        start = start or Pose2D(0.0, 0.0, 0.0)
        self.estimate = Estimate(0.0, start.x, start.y, start.theta)
        self.distance = 0.0
        self.residual = np.zeros(robot.n_wheels)
        self._pose = start
        self._last: SensorSample | None = None
        self._t = 0.0
        self._still_for = STILL_TIME  # standing until a wheel turns (STILL_TIME)
        self._vel = (0.0, 0.0, 0.0)
        self._acc_world: tuple[float, ...] = (0.0, 0.0, 0.0)
        self.body_velocity = np.zeros(3)
        """Low-passed body-frame twist (vx, vy m/s, w rad/s)."""
        self.body_acceleration = np.zeros(3)
        """Low-passed acceleration in the body frame (m/s^2, rad/s^2): what drives the slip model."""
        self._accel = 0.0
        self._history: deque[tuple[float, float, float, float]] = deque()
        self._track_mismatch = 0.0

    def _init_wheel_odometry(self, robot: RobotDescription, slip: SlipParameters | None) -> None:
        """The driven wheels' forward kinematics, resolution and slip model (none without an encoder
        on every wheel)."""
        if not self.has_encoders:
            self.slip_model = None
            self.rotation_resolution = 0.0
            return
        cpr = {e.wheel: e.counts_per_rev for e in robot.encoders.motors}
        self._rad_per_count = np.array([2.0 * math.pi / cpr[w.name] for w in robot.wheels])
        self._J = robot.wheel_matrix
        self._pinv = forward_matrix(robot)
        per_count = np.abs(self._pinv[2]) * self._rad_per_count
        self.rotation_resolution = float(per_count.max())
        self.wheel_slip = WheelSlipCheck(self._J, self._rad_per_count)
        """The fit residual's slip check (four wheels or more; :mod:`~omnibot.estimation.wheelslip`)."""
        self.wheel_skid = WheelSlipCheck(self._J, self._rad_per_count, window=0.0, margin=SKID_MARGIN)
        """A gross slip in one interval: what the heading filter is told of the residual."""
        self.slip_model = SlipModel(robot, slip) if slip is not None else None

    def reset(self, pose: Pose2D) -> None:
        """Put the estimate at ``pose`` (keeps the gyro's learned bias and scale)."""
        self._pose = pose
        self._still_theta = pose.theta - self.silence.turned
        self.filter.reset_heading(pose.theta)
        e = self.estimate
        self.estimate = Estimate(e.t, pose.x, pose.y, pose.theta, 0.0, 0.0, 0.0, e.slipping, e.standstill)

    def update(self, sample: SensorSample) -> Estimate:
        """Fold in one telemetry sample; returns the new estimate."""
        last = self._last
        self._last = sample
        if last is None:
            self._t = sample.controller_time
            self.estimate = Estimate(self._t, *self.estimate_pose_tuple())
            return self.estimate
        dt_ms = (round(sample.controller_time * 1000) - round(last.controller_time * 1000)) % COUNT_MODULUS
        dt = dt_ms / 1000.0
        self._t += dt
        if dt <= 0:
            return self.estimate

        wheel, moved, slip, skid = self._driven(sample, last, dt)
        rolled = None
        if self.tracking is not None and sample.tracking is not None and last.tracking is not None:
            delta = count_delta(np.asarray(sample.tracking, float), np.asarray(last.tracking, float))
            moved |= bool(np.any(delta != 0))
            rolled = delta * self.tracking.m_per_count
        self._still_for = 0.0 if moved else self._still_for + dt
        standstill = self._still_for >= STILL_TIME
        if rolled is not None and wheel is not None and self._tracking_slip(rolled, wheel, dt):
            slip = skid = True

        d_theta = self._rotation(dt, sample, last, wheel, standstill, skid, self._accel)
        if self.translation == "tracking":
            if rolled is None or self.tracking is None:
                dx = dy = 0.0
            else:
                dx, dy = self.tracking.displacement(rolled, d_theta)
        elif wheel is not None:
            dx, dy = wheel[0], wheel[1]
        else:
            dx = dy = 0.0
        if standstill:
            dx = dy = 0.0
        before = self._pose
        self._pose = compose_arc(before, dx, dy, d_theta)
        self.distance += math.hypot(dx, dy)
        self._low_pass(before, d_theta, dt)
        self._body_rates()
        self._accel = self._acceleration()
        slipping = slip or self.filter.slipping
        # the low-pass lags a changing velocity by VELOCITY_TAU; its acceleration puts that back
        (vx, vy, w), (ax, ay, aw) = self._vel, self._acc_world
        tau = VELOCITY_TAU
        self.estimate = Estimate(
            self._t,
            *self.estimate_pose_tuple(),
            vx + tau * ax,
            vy + tau * ay,
            w + tau * aw,
            slipping,
            standstill,
        )
        return self.estimate

    def _driven(
        self, sample: SensorSample, last: SensorSample, dt: float
    ) -> tuple[tuple[float, float, float] | None, bool, bool, bool]:
        """The body's motion (dx, dy, dtheta) by the driven wheels' counts since ``last`` (corrected by
        the slip model; None without encoders), whether a wheel turned, and whether their fit's
        residual says a wheel slipped over the last window, and skidded over this interval (four
        wheels or more)."""
        if not (self.has_encoders and sample.encoders is not None and last.encoders is not None):
            return None, False, False, False
        counts = count_delta(np.asarray(sample.encoders, float), np.asarray(last.encoders, float))
        moved = bool(np.any(counts != 0))
        angles = counts * self._rad_per_count
        if self.slip_model is not None:
            q, acc = self.body_velocity, self.body_acceleration
            model = self.slip_model
            angles = angles * model.params.scale - model.wheel_correction(q, acc) * dt
        disp = self._pinv @ angles
        self.residual = angles - self._J @ disp
        slip = self.wheel_slip.update(angles, dt)
        skid = self.wheel_skid.update(angles, dt)
        return (float(disp[0]), float(disp[1]), float(disp[2])), moved, slip, skid

    def _tracking_slip(self, rolled: np.ndarray, wheel: tuple[float, float, float], dt: float) -> bool:
        """Tracking wheels against driven wheels: a translation slip the gyro cannot see (their gap,
        decaying over :data:`TRACK_SLIP_WINDOW`, beyond a floor plus a share of the travel)."""
        assert self.tracking is not None
        tx, ty = self.tracking.displacement(rolled, wheel[2])
        gap = math.hypot(tx - wheel[0], ty - wheel[1])
        window = TRACK_SLIP_WINDOW
        self._track_mismatch = self._track_mismatch * math.exp(-dt / window) + gap
        travelled = math.hypot(tx, ty) / dt * window
        return self._track_mismatch > TRACK_SLIP_GAP + TRACK_SLIP_FRACTION * travelled

    def _low_pass(self, before: Pose2D, d_theta: float, dt: float) -> None:
        """The world velocity low-passed over :data:`VELOCITY_TAU` from the step ``before`` -> the pose,
        and its acceleration over :data:`ACCEL_TAU`."""
        a = 1.0 - math.exp(-dt / VELOCITY_TAU)
        vx0, vy0, w0 = self._vel
        self._vel = (
            vx0 + a * ((self._pose.x - before.x) / dt - vx0),
            vy0 + a * ((self._pose.y - before.y) / dt - vy0),
            w0 + a * (d_theta / dt - w0),
        )
        b = 1.0 - math.exp(-dt / ACCEL_TAU)
        self._acc_world = tuple(
            acc + b * ((new - old) / dt - acc)
            for acc, new, old in zip(self._acc_world, self._vel, (vx0, vy0, w0), strict=True)
        )

    def _body_rates(self) -> None:
        """The low-passed world velocity and acceleration in the body frame (the acceleration is the
        inertial one, what the wheels must push for, also while the body turns)."""
        theta = self._pose.theta
        self.body_velocity = world_to_body(self._vel, theta)
        self.body_acceleration = world_to_body(self._acc_world, theta)

    def _acceleration(self) -> float:
        """Second difference of the pose over ACCEL_SPAN: |a| + 0.2 m x |alpha|."""
        h = self._history
        p = self._pose
        h.append((self._t, p.x, p.y, p.theta))
        while len(h) > 2 and h[1][0] <= self._t - 2.0 * ACCEL_SPAN:
            h.popleft()
        t0 = h[0][0]
        if self._t - t0 < 2.0 * ACCEL_SPAN - 1e-6:
            return self._accel
        mid = min(h, key=lambda r: abs(r[0] - (t0 + self._t) / 2.0))
        t1, t2 = mid[0] - t0, self._t - mid[0]
        if t1 <= 0 or t2 <= 0:
            return self._accel
        span = 0.5 * (t1 + t2)

        def second(i: int, now: float) -> float:
            return ((now - mid[i]) / t2 - (mid[i] - h[0][i]) / t1) / span

        acc = math.hypot(second(1, p.x), second(2, p.y))
        return acc + 0.2 * abs(second(3, p.theta))

    def estimate_pose_tuple(self) -> tuple[float, float, float]:
        """The current pose as ``(x, y, theta)`` (m, m, rad)."""
        p = self._pose
        return (p.x, p.y, p.theta)

    def _rotation(
        self,
        dt: float,
        sample: SensorSample,
        last: SensorSample,
        wheel: tuple[float, float, float] | None,
        standstill: bool,
        slip: bool,
        accel: float,
    ) -> float:
        d_ref = wheel[2] if wheel is not None else None
        if self.heading_source == "encoders" or self.silence.silent:
            return d_ref or 0.0
        if sample.heading is None or last.heading is None:
            return d_ref or 0.0
        silence = self.silence
        if silence.update(sample.heading, d_ref):
            self.alerts.append(
                f"{silence.finding()}; heading from the wheel encoders from now on (describe "
                f"{self.robot_name} without a gyro for this controller: docs/navigation.md)"
            )
            # the heading stood still since the gyro's last change: the encoders' rotation replaces it
            return self._still_theta + silence.turned - self._pose.theta
        d_psi = sample.heading - last.heading
        if self.heading_source == "gyro":
            d_theta = d_psi
        else:
            d_theta = self.filter.update(
                dt,
                d_psi,
                d_ref,
                standstill=standstill,
                slip=slip,
                accel=accel,
                speed=0.0 if wheel is None or dt <= 0 else math.hypot(wheel[0], wheel[1]) / dt,
                ref_resolution=self.rotation_resolution,
            )
        if silence.turned == 0.0:  # the gyro's heading changed: the still stretch starts here
            self._still_theta = self._pose.theta + d_theta
        return d_theta
