"""Closed-loop wheel-speed control (MODE bit 1): feedforward power plus PI on each wheel's speed.

Wheel speeds come from the motor encoders (counts per wheel revolution from the robot description),
measured every ``period_us``. The integral is frozen while the output saturates (anti-windup), and
after a step in a wheel's target (a jump larger than ``band`` in one period: a MOVE from rest, a VEL
that changes the speed at once) it grows at ``1 / (1 + (err / band)^2)`` of its rate until the wheel
reaches the target (its error changes sign: PX4's rate-loop I factor, which answers the same
bounce-back after a large setpoint change): the lag of the rise, a motor at its driver's current
limit the firmware cannot see, is then not stored to carry the wheel past its target. Never 0, so a
steady error the feedforward leaves is still removed. The rise lasts until the target is reached,
not only until the wheel is within ``band``: the last band of the rise is lag too, and at the held
target's rate (below) it was learned twice over (mecanum4's step to 0.8 m/s sideways on carpet: the
wheel 9.7 % past its target, 6.8 % since). After the controller's own slew (:meth:`rise`, no step to
take the sign of) the rise ends within ``band``. Targets that move by small steps (a host's ramp, a
turning body) integrate at the full rate, as before.

Once a wheel's target has not changed for :data:`STEADY_PERIODS` periods (a held VEL, a MOVE's
cruise), and not before a step's rise is over, the integral grows at ``ki_steady / ki`` of its rate
(the correction stays ``ki`` times the integral, so it does not jump): what is left then is the
feedforward's steady error on the floor (-12 % to +35 % of the power), with nothing for the body to
follow, and it is learned that much sooner. While the target moves (a ramp, a tracker's
corrections, a turning body) the loop answers as before: twice the gains everywhere had the wheels
follow every swing of a host's commands. A wheel asked to stand still integrates at the plain rate.

The integral learns the error against the target the period was driven for (the last period's),
not the target just set: the speed read now is the answer to that one. Against the new target a
wheel that follows a host's ramp (a target one VEL step ahead every VEL) read one step short all
the way up, and the integral stored that lag as if it were the floor's error, then carried the
wheel past the ramp's end: mecanum4's 0.3 m/s `cmd_vel` 8 % over and settled within 5 % only after
0.32-0.34 s, 0.16-0.18 s since (issue 24). The P term answers the new target at once.
"""

import math

STEADY_PERIODS = 5
"""Periods a wheel's target must hold still before its integral grows at the steady rate."""


def steady_rate(ki: float, ki_steady: float) -> float:
    """A held target's integral rate in the plain one: ``ki_steady / ki`` (1 without either gain)."""
    return ki_steady / ki if ki > 0.0 and ki_steady > 0.0 else 1.0


class SpeedControl:
    """PI correction of the feedforward powers from encoder-measured wheel speeds."""

    def __init__(
        self,
        cpr: list[int],
        kp: float,
        ki: float,
        period_us: int,
        pwm_max: int,
        band: float = 0.0,
        ki_steady: float = 0.0,
    ) -> None:
        self.n = len(cpr)
        self.rad_per_count = [2.0 * math.pi / c if c > 0 else 0.0 for c in cpr]
        self.kp = kp
        self.ki = ki
        self.period_us = period_us
        self.pwm_max = pwm_max
        self.band = band  # rad/s; 0: every error integrates at the full rate
        self.steady = steady_rate(ki, ki_steady)
        """The integral's rate on a held target, in its rate on a moving one (1: the same)."""
        self.speed = [0.0] * self.n
        self.correction = [0.0] * self.n
        self._integ = [0.0] * self.n
        self._last = [0] * self.n
        self._prev = [0.0] * self.n  # the targets of the last period
        self._rising = [False] * self.n  # after a step, until the wheel reaches its target
        self._toward = [0] * self.n  # the sign of the error a step left (0: a slew, ended within band)
        self._held = [0] * self.n  # periods the target has not changed (up to STEADY_PERIODS)
        self._acc_us = 0

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
            self._toward[i] = 0
            self._held[i] = 0
        self._acc_us = 0

    def due(self, dt_us: int) -> bool:
        """Whether :meth:`update` with ``dt_us`` ends a period (the only time it reads its counts)."""
        return self._acc_us + dt_us >= self.period_us

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
        for i in range(self.n):
            c = counts[i]
            self.speed[i] = (c - self._last[i]) * self.rad_per_count[i] / dt
            self._last[i] = c
            err = target[i] - self.speed[i]
            late = self._prev[i] - self.speed[i]  # against the target the period was driven for
            self.correction[i] = self.kp * err + self.ki * self._integ[i]
            p = ff[i] + self.correction[i]
            jump = target[i] - self._prev[i]
            self._prev[i] = target[i]
            if jump > band or jump < -band:
                self._rising[i] = band > 0.0
                self._toward[i] = 0 if band <= 0.0 else 1 if err > 0.0 else -1
            elif self._toward[i] != 0:
                if err * self._toward[i] <= 0.0:  # reached
                    self._rising[i] = False
                    self._toward[i] = 0
            elif -band <= err <= band:
                self._rising[i] = False
            if jump != 0.0 or target[i] == 0.0 or self._rising[i]:
                self._held[i] = 0
            elif self._held[i] < STEADY_PERIODS:
                self._held[i] += 1
            if -lim < p < lim:
                if self._rising[i]:
                    x = err / band
                    self._integ[i] += late * dt / (1.0 + x * x)
                elif self._held[i] >= STEADY_PERIODS:
                    self._integ[i] += self.steady * late * dt
                else:
                    self._integ[i] += late * dt
            out[i] = self._limit(p)
        return True

    def rise(self) -> None:
        """Take every wheel as after a step (the controller slews its targets at the robot's
        acceleration limits: a step spread over time): large errors integrate less until the wheel is
        within ``band`` of its target."""
        for i in range(self.n):
            self._rising[i] = self.band > 0.0
            self._toward[i] = 0

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
