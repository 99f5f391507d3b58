"""Wheels that turn while the body does not: a stall against an obstacle.

Pinned against a cabinet, a robot's wheels spin on the floor and its encoders say it drives on; an
estimate that believes them reaches the path's end while the robot stands metres short of it. The
encoders (driven wheels, least-squares forward kinematics) say how far the body went; witnesses that
do not turn with the wheels say whether it went anywhere:

* the **gyro**: the body did not turn while the wheels turned it (a gyro that says nothing at all,
  :mod:`~omnibot.estimation.silence`, is no witness);
* the passive **tracking wheels**: the body did not move while the wheels moved it;
* a **sonar**: the range to what is within :data:`SONAR_NEAR` ahead stood still while the wheels
  closed on it by :data:`SONAR_CLOSE`, or the wheels went :data:`SONAR_GAP` beyond its last range
  (through it) with no echo since;
* the simulator's **truth**, where there is one: the body stood still;
* the wheels' **effort**: for :data:`EFFORT_WINDOW` s on end a wheel at full power (the wheel-speed
  loop's or the calibration's) turned at less than :data:`EFFORT_FREE` of its free-running speed
  (:func:`~omnibot.control.reach.free_wheel_speeds`) and :data:`EFFORT_SPEED` of the speed it was
  asked for, and no witness of the translation saw the body move: a motor that pushes the body
  against a wall and cannot slip its wheel there (mecanum4: 3 % of its free speed on carpet, 13 % on
  wood). A robot with no other witness of its translation (mecanum4) has this one. A wheel that does
  slip at full power (omni4's: 30 % of its free speed) turns as fast as it does driving at a carpet's
  reach: its effort tells nothing, the other witnesses must.

"Still" is absolute: over the last :data:`WINDOW` s the wheels say the body moved at least
:data:`MOVING` m/s (or turned :data:`TURNING` rad/s) and the witness saw it move less than
:data:`STILL` m/s (turn less than :data:`STILL_TURN` rad/s). A floor that lets the wheels slip
(a heavy robot on carpet, open loop) makes the body slower than its wheels, not still; a stall is
evidence from a witness for :data:`HOLD` s on end. Thresholds were set on the simulator (lockstep,
docs/navigation.md "Stalls"): no evidence on normal follows of the three presets on wood and carpet.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from omnibot.control import free_wheel_speeds
from omnibot.estimation.estimator import SensorSample
from omnibot.estimation.odometry import COUNT_MODULUS, count_delta
from omnibot.estimation.silence import GyroSilence
from omnibot.estimation.tracking import TrackingGeometry
from omnibot.motion import Pose2D, Twist
from omnibot.robot import RobotDescription, SonarSpec, kinematics

WINDOW = 0.4
"""s of telemetry the encoders and a witness are compared over."""
HOLD = 0.4
"""s a witness's evidence must last to call a stall."""
MOVING = 0.15
"""m/s the wheels must say the body moved at (over :data:`WINDOW`) for the translation to count."""
TURNING = 0.5
"""rad/s the wheels must say the body turned at for the rotation to count."""
STILL = 0.04
"""m/s below which a witness saw the body stand still."""
STILL_TURN = 0.1
"""rad/s below which a witness saw the body not turn."""
SONAR_NEAR = 0.2
"""m: a sonar witnesses only what is this close (farther, a person walking ahead keeps the range)."""
SONAR_CLOSE = 0.08
"""m the wheels must close on a sonar's range while it stands still."""
SONAR_GAP = 0.05
"""m beyond a sonar's last range the wheels must go, with no echo since, to have gone through it."""
SONAR_STEADY = 0.03
"""m a sonar's range may wander (noise) and still count as the same obstacle standing still."""
SONAR_TURN = 0.2
"""rad the wheels may turn the body before a sonar's last range is no longer the one ahead."""
EFFORT_POWER = 0.97
"""Share of the largest power at which a wheel counts as at full power."""
EFFORT_FREE = 0.2
"""Share of its free-running speed below which a wheel at full power counts as held back (driving at a
carpet's reach at full power, mecanum4's turn at 40-50 %)."""
EFFORT_SPEED = 0.75
"""... and share of the speed it was asked for (a wheel asked to go slowly is not held back)."""
EFFORT_WINDOW = 0.5
"""s every sample must show a held-back wheel at full power for the effort to witness a stall."""
TARGET_AGE = 0.3
"""s a commanded twist stays the wheels' target (a VEL's watchdog ends it on the controller too)."""


class StallSample(SensorSample, Protocol):
    """What the detector reads of a telemetry sample (the client's ``Telemetry`` has it all): what an
    estimator reads, and more."""

    @property
    def time(self) -> float:
        """Link clock, s."""

    @property
    def gyro_rate(self) -> float | None:
        """The gyro's rate, rad/s."""

    @property
    def powers(self) -> tuple[int, ...] | None:
        """Applied motor powers, counts."""

    @property
    def ranges(self) -> tuple[float | None, ...] | None:
        """Each sonar's last range, m (None: no echo)."""


@dataclass(frozen=True)
class Stall:
    """A stall found: when (link clock), by which witness, and in words."""

    t: float
    witness: str
    text: str


@dataclass
class _Step:
    """One sample's increments: what the wheels say and what each witness saw (None: no witness)."""

    t: float
    dt: float
    moved: float  # m, the wheels' translation
    turned: float  # rad, the wheels' rotation
    gyro: float | None = None
    tracked: float | None = None
    truth_moved: float | None = None
    truth_turned: float | None = None
    effort: float | None = None  # the held-back wheel's share of its asked speed, None: none held back


class _Sonar:
    """One sonar: the range the wheels' approach is measured from (along its axis), its last reading."""

    def __init__(self, spec: SonarSpec) -> None:
        self.spec = spec
        self.cos, self.sin = math.cos(spec.angle), math.sin(spec.angle)
        self.anchor: float | None = None  # m: a range that has not shrunk since (as the wheels say)
        self.closed = 0.0  # m the wheels closed on it since
        self.echo = False  # a reading has come since the anchor
        self.last: float | None = None  # m: the last reading
        self.since = 0.0  # m the wheels closed since the last reading
        self.turned = 0.0  # rad the wheels turned since the anchor

    def update(self, dx: float, dy: float, dtheta: float, reading: float | None) -> str:
        """Fold in the wheels' body-frame step and this sample's reading; what it witnesses ("")."""
        step = dx * self.cos + dy * self.sin
        self.closed += step
        self.since += step
        self.turned += dtheta
        if abs(self.turned) > SONAR_TURN:
            self.anchor = self.last = None  # the body turned away: what was ahead is not now
        if reading is not None:
            self.last, self.since = reading, 0.0
            a = self.anchor
            shrunk = a is not None and reading < a - 0.25 * max(self.closed, 0.0) - SONAR_STEADY
            if a is None or self.closed < 0.0 or shrunk or reading > a + SONAR_STEADY:
                self.anchor, self.closed, self.turned, self.echo = reading, 0.0, 0.0, False
            else:
                self.echo = True
        last, a = self.last, self.anchor
        if last is not None and last <= SONAR_NEAR and self.since >= last + SONAR_GAP:
            return (
                f"sonar: the wheels went {100 * self.since:.0f} cm towards what sonar {self.spec.name} "
                f"last saw {100 * last:.0f} cm ahead"
            )
        if a is not None and a <= SONAR_NEAR and self.echo and self.closed >= SONAR_CLOSE:
            return (
                f"sonar: sonar {self.spec.name}'s range stands at {100 * a:.0f} cm while the wheels "
                f"close {100 * self.closed:.0f} cm on it"
            )
        return ""


class StallDetector:
    """Finds stalls in a robot's telemetry (see the module docstring): :meth:`command` with each twist
    sent, :meth:`update` with each sample (and the truth's pose, where there is one)."""

    def __init__(self, robot: RobotDescription) -> None:
        cpr = {e.wheel: e.counts_per_rev for e in robot.encoders.motors}
        self.able = all(w.name in cpr for w in robot.wheels)
        """The robot has an encoder on every driven wheel (without, nothing is ever found)."""
        self._rad_per_count = np.array([2.0 * math.pi / cpr.get(w.name, 1) for w in robot.wheels])
        self._J = robot.wheel_matrix
        self._pinv = kinematics.forward_matrix(robot)
        self._power_max = min(w.motor.pwm_max for w in robot.wheels)
        self._free = free_wheel_speeds(robot)
        self._min_speed = MOVING / max(w.radius for w in robot.wheels)  # rad/s a wheel is asked at least
        self._tracking = (
            TrackingGeometry(robot.encoders.tracking, robot.name)
            if len(robot.encoders.tracking) >= 2
            else None
        )
        self._gyro = robot.gyro is not None
        self.silence = GyroSilence()
        self._sonars = [_Sonar(s) for s in robot.sonars]
        self._steps: deque[_Step] = deque()
        self._last: StallSample | None = None
        self._last_truth: Pose2D | None = None
        self._target: np.ndarray | None = None
        self._target_t = -math.inf
        self._since: float | None = None
        self.evidence = ""
        """The witness that gives evidence now and what it says ("name: words"; "" for none)."""
        self.stall: Stall | None = None
        """The stall found, until the evidence ends (then the detector looks for the next one)."""

    def command(self, t: float, twist: Twist | None) -> None:
        """The twist sent at link time ``t`` (None: none sent): the wheels' target speeds."""
        if twist is not None:
            self._target = self._J @ np.array([twist.vx, twist.vy, twist.w])
            self._target_t = t

    def update(self, sample: StallSample, truth: Pose2D | None = None) -> Stall | None:
        """Fold in one sample (``truth``: the body's true pose then, if known); the stall found on
        this sample (once per stall), else None."""
        last, self._last = self._last, sample
        last_truth, self._last_truth = self._last_truth, truth
        if not self.able or last is None or sample.encoders is None or last.encoders is None:
            return None
        dt_ms = (round(sample.controller_time * 1000) - round(last.controller_time * 1000)) % COUNT_MODULUS
        dt = dt_ms / 1000.0
        if not 0.0 < dt < 1.0:
            return None
        angles = count_delta(np.asarray(sample.encoders, float), np.asarray(last.encoders, float))
        angles = angles * self._rad_per_count
        dx, dy, dth = (float(v) for v in self._pinv @ angles)
        step = _Step(sample.time, dt, math.hypot(dx, dy), dth)
        self._witness(step, sample, last, dth, truth, last_truth, angles / dt)
        sonar = ""
        ranges = sample.ranges or ()
        for i, s in enumerate(self._sonars):
            found = s.update(dx, dy, dth, ranges[i] if i < len(ranges) else None)
            sonar = sonar or found
        self._steps.append(step)
        while self._steps and self._steps[0].t < sample.time - max(WINDOW, EFFORT_WINDOW):
            self._steps.popleft()
        self.evidence = sonar or self._judge(sample.time)
        if not self.evidence:
            self._since, self.stall = None, None
            return None
        if self._since is None:
            self._since = sample.time
        if self.stall is not None or sample.time - self._since < HOLD:
            return None
        self.stall = Stall(sample.time, self.evidence.split(":", 1)[0], self._words())
        return self.stall

    # ------------------------------------------------------------------ helpers

    def _witness(
        self,
        step: _Step,
        sample: StallSample,
        last: StallSample,
        dth: float,
        truth: Pose2D | None,
        last_truth: Pose2D | None,
        speeds: np.ndarray,
    ) -> None:
        """Fill in what each witness saw over the step."""
        if self._gyro and not self.silence.silent:
            if sample.heading is not None and last.heading is not None:
                self.silence.update(sample.heading, dth)
                step.gyro = sample.heading - last.heading
            elif sample.gyro_rate is not None:
                step.gyro = sample.gyro_rate * step.dt
        if self._tracking is not None and sample.tracking is not None and last.tracking is not None:
            rolled = count_delta(np.asarray(sample.tracking, float), np.asarray(last.tracking, float))
            turned = step.gyro if step.gyro is not None else dth
            step.tracked = math.hypot(
                *self._tracking.displacement(rolled * self._tracking.m_per_count, turned)
            )
        if truth is not None and last_truth is not None:
            step.truth_moved = math.hypot(truth.x - last_truth.x, truth.y - last_truth.y)
            step.truth_turned = truth.theta - last_truth.theta
        target = self._target
        if sample.powers is not None and target is not None and sample.time - self._target_t <= TARGET_AGE:
            asked = np.abs(target)
            power = np.abs(np.asarray(sample.powers, float))
            share = speeds * np.sign(target) / np.maximum(asked, 1e-9)
            held = (
                (asked >= max(0.5 * float(asked.max()), self._min_speed))
                & (power >= EFFORT_POWER * self._power_max)
                & (np.abs(speeds) < EFFORT_FREE * self._free)
                & (share < EFFORT_SPEED)
            )
            step.effort = float(share[held].min()) if held.any() else None

    def _judge(self, now: float) -> str:
        """The witness that says, over the window, that the body stood still while the wheels moved it."""
        steps = [s for s in self._steps if s.t > now - WINDOW]
        span = sum(s.dt for s in steps)
        if span < 0.75 * WINDOW:
            return ""
        moved = sum(s.moved for s in steps)
        turned = sum(s.turned for s in steps)
        translating, turning = moved >= MOVING * span, abs(turned) >= TURNING * span

        def total(values: list[float | None]) -> float | None:
            return None if any(v is None for v in values) else sum(v for v in values if v is not None)

        truth_moved = total([s.truth_moved for s in steps])
        truth_turned = total([s.truth_turned for s in steps])
        tracked = total([s.tracked for s in steps])
        gyro = total([s.gyro for s in steps])
        if (
            (translating or turning)
            and truth_moved is not None
            and truth_turned is not None
            and truth_moved <= STILL * span
            and abs(truth_turned) <= STILL_TURN * span
        ):
            return "truth: the simulator's truth has the body standing still"
        if translating and tracked is not None and tracked <= STILL * span:
            return "tracking: the tracking wheels do not roll"
        if turning and gyro is not None and abs(gyro) <= STILL_TURN * span:
            return "gyro: the gyro says the body does not turn"
        seen = [v for v in (truth_moved, tracked) if v is not None]
        if any(v > STILL * span for v in seen):
            return ""  # a witness of the translation saw the body move: the effort is the floor's
        recent = [s for s in self._steps if s.t > now - EFFORT_WINDOW]
        if sum(s.dt for s in recent) >= 0.75 * EFFORT_WINDOW and all(s.effort is not None for s in recent):
            worst = max(s.effort for s in recent if s.effort is not None)
            return f"effort: a wheel at full power turns at {100 * max(worst, 0.0):.0f} % of the speed asked"
        return ""

    def _words(self) -> str:
        """The stall in words: what the wheels say and what the witness says."""
        steps = [s for s in self._steps if s.t > self._steps[-1].t - WINDOW]
        span = max(sum(s.dt for s in steps), 1e-9)
        speed = sum(s.moved for s in steps) / span
        rate = round(sum(s.turned for s in steps) / span, 2) + 0.0  # no -0.00
        why = self.evidence.partition(": ")[2]
        return f"stalled: the wheels say {speed:.2f} m/s, {rate:+.2f} rad/s but {why}"
