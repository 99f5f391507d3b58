"""A learned model of how the robot answers velocity commands, to invert in the feedforward.

The controller's power calibration is made on one floor; on another (carpet), or with a wheel-speed
loop that cannot keep up, the robot drives at some other speed than commanded, and differently in
different directions. :class:`VelocityResponse` fits, by recursive least squares with forgetting,

    v_body(t) ~ G u(t - delay)       (2 x 2, translation)        w(t) ~ g u_w(t - delay)

from the commands sent and the velocities the estimator measures, and :meth:`compensate` sends
G^-1 times what is wanted. G starts at the identity and is kept well conditioned (its eigen
values within ``[lo, hi]``, and symmetric: a response turned sideways is heading error or delay,
which feedback handles, not gain); it only learns while the commands excite it.
"""

from __future__ import annotations

import math
from collections import deque

import numpy as np


class VelocityResponse:
    """RLS estimate of the body-velocity response (see the module docstring)."""

    def __init__(
        self,
        *,
        delay: float = 0.06,
        tau: float = 2.0,
        lo: float = 0.6,
        hi: float = 1.6,
        min_speed: float = 0.05,
    ) -> None:
        self.delay = delay
        self.tau = tau
        self.lo, self.hi = lo, hi
        self.min_speed = min_speed
        self.G = np.eye(2)
        self.g_w = 1.0
        self._P = np.eye(2) * 0.5
        self._Pw = 0.5
        self._sent: deque[tuple[float, float, float, float]] = deque()

    def reset(self) -> None:
        """Forget what was learned: unit gains, initial uncertainty, no commands remembered."""
        self.G = np.eye(2)
        self.g_w = 1.0
        self._P = np.eye(2) * 0.5
        self._Pw = 0.5
        self._sent.clear()

    def sent(self, t: float, vx: float, vy: float, w: float) -> None:
        """Remember a command as sent at time ``t``."""
        self._sent.append((t, vx, vy, w))

    def observe(self, t: float, vx: float, vy: float, w: float, dt: float) -> None:
        """Fold in the measured body velocity at time ``t`` against the command of ``delay`` ago."""
        sent = self._sent
        while len(sent) > 1 and sent[1][0] <= t - self.delay:
            sent.popleft()
        if not sent or sent[0][0] > t - self.delay:
            return
        _, ux, uy, uw = sent[0]
        lam = math.exp(-dt / self.tau)
        u = np.array([ux, uy])
        if math.hypot(ux, uy) >= self.min_speed:
            P = self._P
            Pu = P @ u
            k = Pu / (lam + u @ Pu)
            y = np.array([vx, vy])
            self.G = self.G + np.outer(y - self.G @ u, k)
            self._P = (P - np.outer(k, Pu)) / lam
            if np.trace(self._P) > 10.0:
                self._P *= 10.0 / np.trace(self._P)
            self._condition()
        if abs(uw) >= 0.1:
            pw = self._Pw
            kw = pw * uw / (lam + uw * pw * uw)
            self.g_w = float(min(self.hi, max(self.lo, self.g_w + kw * (w - self.g_w * uw))))
            self._Pw = float(min(10.0, (pw - kw * uw * pw) / lam))

    def _condition(self) -> None:
        # keep G symmetric positive definite: a rotation-like mismatch comes from heading error or
        # delay, which the feedback handles, and inverting it would turn every command
        sym = 0.5 * (self.G + self.G.T)
        vals, vecs = np.linalg.eigh(sym)
        self.G = vecs @ np.diag(np.clip(vals, self.lo, self.hi)) @ vecs.T

    def compensate(self, vx: float, vy: float, w: float) -> tuple[float, float, float]:
        """The command that should produce (vx, vy, w)."""
        ux, uy = np.linalg.solve(self.G, np.array([vx, vy]))
        return float(ux), float(uy), w / self.g_w
