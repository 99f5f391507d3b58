"""PID with anti-windup and a filtered derivative.

::

    u = kp e + ki integral(e) + kd de/dt (low-passed with time constant d_tau), clamped to [lo, hi]

Anti-windup by conditional integration: while the output is clamped, the integral only moves in the
direction that brings the output back inside (and never beyond ``i_limit`` in size). The derivative
can act on the measurement instead of the error (pass ``measurement``), so a setpoint step does not
kick the output; its first-order filter keeps encoder quantisation from turning into spikes.
"""

from __future__ import annotations

import math


class PID:
    """A discrete PID controller; call :meth:`update` once per control period."""

    def __init__(
        self,
        kp: float,
        ki: float = 0.0,
        kd: float = 0.0,
        *,
        lo: float = -math.inf,
        hi: float = math.inf,
        i_limit: float = math.inf,
        d_tau: float = 0.0,
    ) -> None:
        if lo >= hi:
            raise ValueError(f"PID output range is empty: lo {lo} >= hi {hi}")
        if d_tau < 0 or i_limit < 0:
            raise ValueError("PID d_tau and i_limit must be >= 0")
        self.kp, self.ki, self.kd = kp, ki, kd
        self.lo, self.hi = lo, hi
        self.i_limit = i_limit
        self.d_tau = d_tau
        self.integral = 0.0
        self.derivative = 0.0
        self.output = 0.0
        self._prev: float | None = None

    def reset(self) -> None:
        """Zero the integral, derivative and output, and forget the last measurement."""
        self.integral = 0.0
        self.derivative = 0.0
        self.output = 0.0
        self._prev = None

    def update(self, error: float, dt: float, measurement: float | None = None) -> float:
        """One step with ``error`` = setpoint - measurement over ``dt`` s; returns the clamped output.

        With ``measurement`` the derivative is taken of -measurement (no setpoint kick).
        """
        if dt <= 0:
            return self.output
        signal = -measurement if measurement is not None else error
        if self._prev is not None and self.kd != 0.0:
            raw = (signal - self._prev) / dt
            a = dt / (self.d_tau + dt)
            self.derivative += a * (raw - self.derivative)
        self._prev = signal
        p, d = self.kp * error, self.kd * self.derivative
        trial = self.integral + error * dt
        trial = max(-self.i_limit, min(self.i_limit, trial))
        u = p + self.ki * trial + d
        if (u > self.hi and error * self.ki > 0) or (u < self.lo and error * self.ki < 0):
            trial = self.integral  # clamped and the integral would push further: hold it
            u = p + self.ki * trial + d
        self.integral = trial
        self.output = max(self.lo, min(self.hi, u))
        return self.output
