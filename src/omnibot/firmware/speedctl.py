"""Closed-loop wheel-speed control (MODE bit 1): feedforward power plus PI on each wheel's speed.

Wheel speeds come from the motor encoders (counts per wheel revolution from the robot description),
measured every ``period_us``. The integral is frozen while the output saturates (anti-windup), and
after a step in a wheel's target (a jump larger than ``band`` in one period: a MOVE from rest, a VEL
that changes the speed at once) it grows at ``1 / (1 + (err / band)^2)`` of its rate until the wheel
is within ``band`` of the target (PX4's rate-loop I factor, which answers the same bounce-back after
a large setpoint change): the lag of the rise, a motor at its driver's current limit the firmware
cannot see, is then not stored to carry the wheel past its target. Never 0, so a steady error the
feedforward leaves is still removed. Targets that move by small steps (a host's ramp, a turning
body) integrate at the full rate, as before.
"""

import math

FOLD_TIME = 0.5
"""s: the time constant at which the integral's steady share is folded into the learned gains."""
STEADY_TIME = 0.2
"""s the wheels' targets must have stood still before their integral counts as the floor's share."""
KNOWN_TIME = 0.3
"""s of folding after which a course's (the rotation's) gain is taken as known."""
COURSE_STEP = 15.0
"""degrees between the learned gains' folded courses (0..90)."""


class FloorGain:
    """The floor's share of the closed loop's feedforward, learned while driving (project addition).

    The feedforward's powers come from the power calibration, which maps power to the *body's*
    speed on the floor it was made on; the loop holds the *wheels'* speed, and on another floor (or
    where the rollers creep) the power that takes differs by -12 % to +35 % with the course
    (BENCHMARKS.md). The integral learns that share after every start; here it is kept: whenever the
    wheels' targets have stood still :data:`STEADY_TIME` on a translation that does not turn, the
    integral's share is fitted by least squares (``ki integ_i ~ a T_i``, T_i each wheel's
    translation feedforward) and folded, at :data:`FOLD_TIME`, into a translation gain per folded
    course (knots every :data:`COURSE_STEP` degrees, interpolated), the integral giving up what the
    feedforward takes over (the output does not move). A turning translation applies the gain and
    learns nothing (its slow wheels' share is their dead band, which a split between translation
    and rotation would take for the floor); rotation is not learned (the gyro calibration's spins
    and omni3's clipped-gyro spin changed with it: tests/navigation/test_runner.py). The gains
    persist from one drive to the next (:meth:`reset` on CAL, MODE and at boot), so every start
    after the first on a course of this floor has a feedforward that knows the floor.
    """

    def __init__(self) -> None:
        self.n = int(90.0 / COURSE_STEP) + 1
        self.tr = [1.0] * self.n
        self.known = [0.0] * self.n  # s folded into each course's gain
        self.k = 0  # the last course's knot below and the weight of the knot above
        self.w = 0.0

    def reset(self) -> None:
        """Forget what was learned (a new calibration, mode or floor)."""
        for i in range(self.n):
            self.tr[i] = 1.0
            self.known[i] = 0.0

    def translation(self, folded: float) -> float:
        """The translation gain on the folded course (degrees, 0..90), remembered for :meth:`fold`."""
        x = min(max(folded, 0.0), 90.0) / COURSE_STEP
        k = min(int(x), self.n - 2)
        self.k = k
        self.w = x - k
        return self.tr[k] + self.w * (self.tr[k + 1] - self.tr[k])

    def knows(self, translating: bool, rotating: bool) -> bool:
        """True when the gain of the last course has been learned on a translation that does not turn."""
        if rotating or not translating:
            return False
        return self.known[self.k if self.w < 0.5 else self.k + 1] >= KNOWN_TIME

    def fold(
        self, share: list[float], tr: list[float], rot: list[float], dt: float, out: list[float]
    ) -> None:
        """Fold ``share`` (each wheel's ``ki integ``, PWM counts) into the last course's gain over
        ``dt`` s, given each wheel's translation and rotation feedforward ``tr``, ``rot`` (counts, at
        the present gain; ``tr`` moved to the new one); ``out`` gets each wheel's feedforward change
        (counts), which the integral gives up. Nothing is learned while the body turns."""
        stt = sct = 0.0
        turning = False
        for i in range(len(share)):
            out[i] = 0.0
            stt += tr[i] * tr[i]
            sct += share[i] * tr[i]
            if rot[i] != 0.0:
                turning = True
        if turning or stt == 0.0:
            return
        f = min(dt / FOLD_TIME, 1.0)
        a = sct / stt
        k = self.k
        w = self.w
        old = self.tr[k] + w * (self.tr[k + 1] - self.tr[k])
        self.tr[k] *= 1.0 + f * (1.0 - w) * a
        self.tr[k + 1] *= 1.0 + f * w * a
        self.known[k] += (1.0 - w) * dt
        self.known[k + 1] += w * dt
        g = (self.tr[k] + w * (self.tr[k + 1] - self.tr[k])) / old
        for i in range(len(share)):
            out[i] = tr[i] * (g - 1.0)
            tr[i] *= g


class SpeedControl:
    """PI correction of the feedforward powers from encoder-measured wheel speeds."""

    def __init__(
        self, cpr: list[int], kp: float, ki: float, period_us: int, pwm_max: int, band: float = 0.0
    ) -> None:
        self.n = len(cpr)
        self.rad_per_count = [2.0 * math.pi / c if c > 0 else 0.0 for c in cpr]
        self.kp = kp
        self.ki = ki
        self.period_us = period_us
        self.pwm_max = pwm_max
        self.band = band  # rad/s; 0: every error integrates at the full rate
        self.speed = [0.0] * self.n
        self.correction = [0.0] * self.n
        self._integ = [0.0] * self.n
        self._last = [0] * self.n
        self._prev = [0.0] * self.n  # the targets of the last period
        self._rising = [False] * self.n  # after a step, until the wheel is within band of its target
        self._acc_us = 0
        self._still_us = 0  # how long the targets have stood still
        self.planned = False
        """A planned acceleration runs on a feedforward that knows the floor: the integral holds."""
        self.steady = False
        """The last period's targets had stood still :data:`STEADY_TIME` (none rising or saturated)."""
        self.floor = FloorGain()
        self._share = [0.0] * self.n
        self._moved = [0.0] * self.n

    @property
    def available(self) -> bool:
        """True when every motor has an encoder."""
        return all(r != 0.0 for r in self.rad_per_count)

    def reset(self, counts: list[int]) -> None:
        """Start afresh from these encoder ``counts``: no integral, no correction, the wheels taken
        as at rest (a target that starts them is a step)."""
        for i in range(self.n):
            self._integ[i] = 0.0
            self.correction[i] = 0.0
            self._last[i] = counts[i]
            self._prev[i] = 0.0
            self._rising[i] = False
        self._acc_us = 0
        self._still_us = 0
        self.steady = False

    def update(
        self, dt_us: int, counts: list[int], target: list[float], ff: list[float], out: list[int]
    ) -> bool:
        """Accumulate time; every period write ff + PI into ``out``; True when it did."""
        self._acc_us += dt_us
        if self._acc_us < self.period_us:
            return False
        dt = self._acc_us * 1e-6
        self._acc_us = 0
        lim = self.pwm_max
        band = self.band
        still = True
        for i in range(self.n):
            if target[i] != self._prev[i]:
                still = False
        self._still_us = self._still_us + self.period_us if still else 0
        steady = self._still_us >= STEADY_TIME * 1e6 and not self.planned
        for i in range(self.n):
            c = counts[i]
            self.speed[i] = (c - self._last[i]) * self.rad_per_count[i] / dt
            self._last[i] = c
            err = target[i] - self.speed[i]
            self.correction[i] = self.kp * err + self.ki * self._integ[i]
            p = ff[i] + self.correction[i]
            jump = target[i] - self._prev[i]
            self._prev[i] = target[i]
            if jump > band or jump < -band:
                self._rising[i] = band > 0.0
            elif -band <= err <= band:
                self._rising[i] = False
            if -lim < p < lim and not self.planned:
                if self._rising[i]:
                    x = err / band
                    self._integ[i] += err * dt / (1.0 + x * x)
                else:
                    self._integ[i] += err * dt
            else:
                steady = False
            if self._rising[i]:
                steady = False
            out[i] = self._limit(p)
        self.steady = steady
        return True

    def learn(self, tr: list[float], rot: list[float], ff: list[float], dt: float) -> None:
        """After a steady period (:attr:`steady`): fold the integral's share into the floor's gains
        (:class:`FloorGain`) for the wheels' translation and rotation feedforward ``tr``, ``rot``;
        ``ff`` (the feedforward in use) takes over what the integral gives up."""
        if self.ki <= 0.0:
            return
        share = self._share
        for i in range(self.n):
            share[i] = self.ki * self._integ[i]
        moved = self._moved
        self.floor.fold(share, tr, rot, dt, moved)
        for i in range(self.n):
            ff[i] += moved[i]
            self._integ[i] -= moved[i] / self.ki

    def rise(self) -> None:
        """Take every wheel as after a step (the controller slews its targets at the robot's
        acceleration limits: a step spread over time): large errors integrate less until the wheel is
        within ``band`` of its target."""
        for i in range(self.n):
            self._rising[i] = self.band > 0.0

    def hold(self, ff: list[float], out: list[int]) -> None:
        """New feedforward between periods: write it plus the last correction (not the bare
        feedforward, which would drop the loop's work until the next period)."""
        for i in range(self.n):
            out[i] = self._limit(ff[i] + self.correction[i])

    def _limit(self, p: float) -> int:
        lim = self.pwm_max
        if p >= lim:
            return lim
        if p <= -lim:
            return -lim
        return round(p)
