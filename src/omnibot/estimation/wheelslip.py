"""One wheel slipping, seen in the least-squares fit of the body twist to the wheels' encoders.

With more wheels than the three planar motions the fit ``q = J^+ a`` leaves a residual ``(I - H) a``
(``H = J J^+``, the fit's hat matrix) that no rigid motion explains. A wheel ``i`` that slips by
``s`` (rad) shows in its own residual by only ``(1 - H_ii) s``: the fit moves the body to take up
the rest (omni4 and mecanum4: ``H_ii = 3/4``, a quarter of the slip, spread over all four wheels as
the same quarter). The studentised residual ``r_i / (1 - H_ii)`` is the whole slip ``s`` again,
were wheel ``i`` the one that slipped (with one spare wheel the four say the same: which wheel it
was cannot be told).

:class:`WheelSlipCheck` sums the increments over a short window (:data:`WINDOW`) before the fit:
the increments telescope, so every wheel's sum is within one count of its true angle however long
the window, while a slip adds up. Its threshold is that bound carried through the studentised
residual, ``max_i sum_j |(I - H)_ij| / (1 - H_ii) * rad_per_count_j`` (omni4, mecanum4: 4 counts),
times :data:`MARGIN`. Quiet stretches of the simulator's runs (no wheel slipping more than 0.01 m/s)
reach the bound and never pass it; ``benchmarks.slip_flag`` measures the rest.
"""

from __future__ import annotations

from collections import deque

import numpy as np
from numpy.typing import ArrayLike, NDArray

from omnibot.robot.kinematics import pseudo_inverse

FloatArray = NDArray[np.float64]

WINDOW = 0.1
"""s of increments summed before the fit (the heading filter's slip window too): a wheel slipping
by 0.025 m/s at omni4's 25 mm radius passes the threshold in it (6 counts)."""
MARGIN = 1.5
"""Threshold over the quantisation bound: what the simulator's quiet stretches reach is the bound
itself (the sum of four counts each within one of its angle, a whole number of counts)."""
SKID_MARGIN = 3.0
"""A skid, for the heading filter: one interval's slip beyond three times the bound (12 counts on
omni4 and mecanum4, the rule the flag had before 2026-12-07: a quarter of it, 3 counts, in the plain
residual). The filter's own gyro check judges smaller slips: with one spare wheel the residual
cannot say how much of a slip turned the body (several wheels slipping at once, as omni4's do
swinging at 1 m/s, mostly do not), and distrusting the wheels' rotation on every small slip left
that swing's heading to the uncalibrated gyro (RMS heading error 0.050 -> 0.060 rad)."""


class WheelSlipCheck:
    """Whether a wheel slipped over the last :data:`WINDOW` s: the studentised fit residual of the
    summed increments beyond the encoders' quantisation (see the module docstring).

    ``wheel_matrix`` (m, 3) maps the body twist to wheel speeds, ``rad_per_count`` (m,) is each
    encoder's resolution; ``window`` 0 checks each increment alone; ``margin`` is the threshold over
    the quantisation bound. With three wheels or fewer there is no residual and :meth:`update` is
    always False."""

    def __init__(
        self,
        wheel_matrix: ArrayLike,
        rad_per_count: ArrayLike,
        window: float = WINDOW,
        margin: float = MARGIN,
    ) -> None:
        J = np.asarray(wheel_matrix, dtype=float)
        m = J.shape[0]
        self.window = window
        self.redundant = m > 3
        hat = J @ pseudo_inverse(J)
        leverage = np.clip(1.0 - np.diag(hat), 1e-12, None)
        self.student = (np.eye(m) - hat) / leverage[:, None]
        """Rows: wheel i's whole slip from the increments, were it the one slipping (0 if m <= 3)."""
        resolution = np.asarray(rad_per_count, dtype=float)
        bound = float((np.abs(self.student) * resolution).sum(axis=1).max()) if self.redundant else 0.0
        self.threshold = margin * bound
        """rad: a wheel's studentised slip over the window beyond which it slips (whole counts on
        omni4 and mecanum4: a slip of exactly the threshold, within rounding, is not beyond it)."""
        self._limit = self.threshold * (1.0 + 1e-9)
        self.slip = np.zeros(m)
        """rad over the window: each wheel's slip, were it the one slipping (all equal in size with
        one spare wheel)."""
        self.slipping = False
        """What the last :meth:`update` said."""
        self._steps: deque[tuple[float, FloatArray]] = deque()
        self._span = 0.0

    def update(self, angles: ArrayLike, dt: float) -> bool:
        """Fold in one interval's wheel increments (rad) ``dt`` s long; whether a wheel slipped."""
        if not self.redundant:
            return False
        step = np.asarray(angles, dtype=float)
        self._steps.append((dt, step))
        self._span += dt
        while len(self._steps) > 1 and self._span - self._steps[0][0] >= self.window - 1e-9:
            self._span -= self._steps.popleft()[0]
        steps = self._steps
        # one interval (window 0: wheel odometry's every update): np.sum's one-row sum, 0.0 + each
        total = steps[0][1] + 0.0 if len(steps) == 1 else np.sum([a for _, a in steps], axis=0)
        self.slip = self.student @ total
        self.slipping = bool(np.abs(self.slip).max() > self._limit)
        return self.slipping
