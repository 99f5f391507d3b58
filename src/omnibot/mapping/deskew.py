"""Motion-distortion correction: a spinning scanner's rays brought to one instant of the base's motion.

A scanner that turns while the robot moves measures ray ``i`` at ``scan.stamp + i *
scan.time_increment``, each from another pose of the base. :func:`scan_points` moves every return
into the base frame at one instant ``at``, assuming the base's body twist (vx, vy, w) constant over
the scan (the exact planar exponential, not a first-order step). With ``time_increment == 0`` and
``at == scan.stamp`` it is :meth:`~omnibot.scan.Scan.points`.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from omnibot.motion import Twist
from omnibot.scan import Scan

FloatArray = NDArray[np.float64]


def motion(twist: Twist, dt: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
    """x, y, theta of the base after ``dt`` (s, an array) at a constant body ``twist``, from its start."""
    th = twist.w * dt
    small = np.abs(th) < 1e-9
    w = np.where(small, 1.0, twist.w)
    sin_w = np.where(small, dt, np.sin(th) / w)
    cos_w = np.where(small, 0.5 * twist.w * dt * dt, (1.0 - np.cos(th)) / w)
    return twist.vx * sin_w - twist.vy * cos_w, twist.vx * cos_w + twist.vy * sin_w, th


def scan_points(scan: Scan, twist: Twist, at: float | None = None) -> FloatArray:
    """The valid returns as (n, 2) points in the base frame at time ``at`` (default: ``scan.stamp``)."""
    ok = scan.valid
    pts = scan.points("base")
    ref = scan.stamp if at is None else at
    dt = scan.stamp + scan.time_increment * np.flatnonzero(ok) - ref
    if not np.any(dt) or twist.is_zero:
        return pts
    x, y, th = motion(twist, dt.astype(np.float64))
    c, s = np.cos(th), np.sin(th)
    out: FloatArray = np.column_stack((c * pts[:, 0] - s * pts[:, 1] + x, s * pts[:, 0] + c * pts[:, 1] + y))
    return out
