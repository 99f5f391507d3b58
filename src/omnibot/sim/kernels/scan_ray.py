"""Where the laser scanner's rays start and point: a ray's time between two rows of the pose
history, the pose there, and the ray's direction from the heading's cos and sin once per row.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from omnibot.sim.kernels.layout import FloatArray

# the rays' table (ray_table): a ray's time from the revolution's start, its direction in the robot's
# base frame, and that direction's cos and sin
RAY_T, RAY_A, RAY_COS, RAY_SIN = 0, 1, 2, 3
RAY_COLUMNS = 4
SMALL_TURN = 0.125
"""rad: how far a ray's heading may have turned from its history row's for its cos and sin to come
from a series about the row's (turned)."""


@njit(cache=True)
def ray_table(ray_t: FloatArray, ray_a: FloatArray) -> FloatArray:
    """The rays measured at times ray_t in directions ray_a as :func:`scan_revolution` takes them:
    one row per ray, its time, angle and the angle's cos and sin (the ``RAY_`` columns)."""
    rays = np.empty((ray_t.shape[0], RAY_COLUMNS))
    for i in range(ray_t.shape[0]):
        a = ray_a[i]
        rays[i, RAY_T], rays[i, RAY_A] = ray_t[i], a
        rays[i, RAY_COS], rays[i, RAY_SIN] = math.cos(a), math.sin(a)
    return rays


@njit(cache=True, inline="always")
def bracket(t: float, hist_t0: float, hist_dt: float, n_hist: int) -> tuple[int, int, float]:
    """(row k, row k1, fraction f): time t lies a fraction f of the way from history row k to k1
    (held outside the history)."""
    pos = (t - hist_t0) / hist_dt
    k = min(max(math.floor(pos), 0), max(n_hist - 2, 0))
    f = min(max(pos - k, 0.0), 1.0) if n_hist > 1 else 0.0
    k1 = k + 1 if n_hist > 1 else k
    return k, k1, f


@njit(cache=True, inline="always")
def lerp(hist_p: FloatArray, k: int, k1: int, f: float, col: int) -> float:
    """Column col of the history, a fraction f of the way from row k to row k1."""
    value: float = hist_p[k, col] + f * (hist_p[k1, col] - hist_p[k, col])
    return value


@njit(cache=True, inline="always")
def turned(c: float, s: float, d: float) -> tuple[float, float]:
    """(cos, sin) of the angle d (|d| <= SMALL_TURN) more than the one whose cos and sin are c, s:
    d's own by their series to d^8 and d^9 (off by less than 3e-16), then turned by it."""
    d2 = d * d
    cd = 1.0 - d2 * (1.0 / 30.0) * (1.0 - d2 * (1.0 / 56.0))  # Horner's, from the innermost term
    cd = 1.0 - d2 * 0.5 * (1.0 - d2 * (1.0 / 12.0) * cd)
    sd = 1.0 - d2 * (1.0 / 42.0) * (1.0 - d2 * (1.0 / 72.0))
    sd = d * (1.0 - d2 * (1.0 / 6.0) * (1.0 - d2 * (1.0 / 20.0) * sd))
    return c * cd - s * sd, s * cd + c * sd


@njit(cache=True, inline="always")
def ray_frame(
    hist_p: FloatArray, k: int, k1: int, f: float, c0: int, ck: float, sk: float, mount_x: float, mount_y: float,
    rays: FloatArray, i: int,
) -> tuple[float, float, float, float, float]:  # fmt: skip
    """(x, y, world angle, its cos, its sin) of ray i of ``rays`` (its direction in the robot's base
    frame, and that angle's cos and sin: columns RAY_A, RAY_COS, RAY_SIN) from the scanner at
    (mount_x, mount_y) on the robot whose pose is history columns c0..c0+2, a fraction f from row k
    to k1; ck, sk: the cos and sin of row k's heading. The heading's turn from row k (at most
    SMALL_TURN) is added to them by a series, and the ray's own angle by its cos and sin: no cos
    and sin called per ray (the directions within 1e-15 of them)."""
    x, y = lerp(hist_p, k, k1, f, c0), lerp(hist_p, k, k1, f, c0 + 1)
    th0 = hist_p[k, c0 + 2]
    d = f * (hist_p[k1, c0 + 2] - th0)
    th = th0 + d
    if abs(d) <= SMALL_TURN:
        ct, st = turned(ck, sk, d)
    else:
        ct, st = math.cos(th), math.sin(th)
    ca, sa = rays[i, RAY_COS], rays[i, RAY_SIN]
    ox, oy = x + ct * mount_x - st * mount_y, y + st * mount_x + ct * mount_y
    return ox, oy, th + rays[i, RAY_A], ct * ca - st * sa, st * ca + ct * sa
