"""Path geometry: Douglas-Peucker simplification, arc-length resampling, curvature, heading rate.

All functions are pure and return new :class:`~omnibot.control.paths.path.Path` objects or arrays.
Turns in place (consecutive points at the same position, different headings) survive resampling.
"""

from __future__ import annotations

import math

import numpy as np

from omnibot.control.paths.path import FloatArray, Path


def douglas_peucker(path: Path, tolerance: float, heading_tolerance: float = math.inf) -> Path:
    """Drop points closer than ``tolerance`` (m) to the chord between the points kept around them.

    A point is also kept when its heading differs from the heading interpolated along the chord by
    more than ``heading_tolerance`` (rad), so a path that turns the body keeps its turns.
    """
    if tolerance < 0:
        raise ValueError(f"tolerance must be >= 0, got {tolerance}")
    n = len(path)
    if n <= 2:
        return path
    keep = np.zeros(n, dtype=bool)
    keep[0] = keep[-1] = True
    x, y, th, s = path.x, path.y, path.theta, path.s
    stack = [(0, n - 1)]
    while stack:
        a, b = stack.pop()
        if b - a < 2:
            continue
        ix = np.arange(a + 1, b)
        dx, dy = x[b] - x[a], y[b] - y[a]
        L = math.hypot(dx, dy)
        if L > 0:
            d = np.abs(dx * (y[ix] - y[a]) - dy * (x[ix] - x[a])) / L
        else:
            d = np.hypot(x[ix] - x[a], y[ix] - y[a])
        span = s[b] - s[a]
        f = (s[ix] - s[a]) / span if span > 0 else (ix - a) / (b - a)
        dh = np.abs(th[ix] - (th[a] + f * (th[b] - th[a])))
        worst_d, worst_h = int(np.argmax(d)), int(np.argmax(dh))
        if d[worst_d] > tolerance:
            k = int(ix[worst_d])
        elif dh[worst_h] > heading_tolerance:
            k = int(ix[worst_h])
        else:
            continue
        keep[k] = True
        stack.append((a, k))
        stack.append((k, b))
    return _subset(path, keep)


def _subset(path: Path, keep: np.ndarray) -> Path:
    return Path(
        path.x[keep],
        path.y[keep],
        path.theta[keep],
        None if path.t is None else path.t[keep],
        None if path.v is None else path.v[keep],
    )


def resample(path: Path, spacing: float, corner: float = math.radians(20)) -> Path:
    """Points every ``spacing`` metres of arc length (ends kept; a piece's last step may be shorter).

    Heading, time and speed are interpolated linearly in arc length. Corners (the direction of
    travel turns by more than ``corner`` rad at one point) and zero-length segments (turns in place)
    are kept: they split the path into pieces that are resampled separately and joined again.
    """
    if spacing <= 0:
        raise ValueError(f"spacing must be > 0, got {spacing}")
    n = len(path)
    if n < 2:
        return path
    steps = np.diff(path.s)
    sharp = np.abs(turning_angles(path)) > corner
    spans: list[tuple[int, int, bool]] = []  # first, last (inclusive), shares its first point
    first, shared = 0, False
    for i in range(1, n):
        if steps[i - 1] <= 0:
            spans.append((first, i - 1, shared))
            first, shared = i, False
        elif sharp[i] and i < n - 1:
            spans.append((first, i, shared))
            first, shared = i, True
    spans.append((first, n - 1, shared))
    columns = {"x": path.x, "y": path.y, "theta": path.theta}
    if path.t is not None:
        columns["t"] = path.t
    if path.v is not None:
        columns["v"] = path.v
    out: dict[str, list[FloatArray]] = {k: [] for k in columns}
    for a, b, skip in spans:
        s = path.s[a : b + 1] - path.s[a]
        if s[-1] <= 0:
            grid = np.array([0.0])
        else:
            count = max(1, math.ceil(s[-1] / spacing - 1e-9))
            grid = np.minimum(np.arange(count + 1) * spacing, s[-1])
            grid[-1] = s[-1]
        if skip:
            grid = grid[1:]
        for key, col in columns.items():
            out[key].append(np.interp(grid, s, col[a : b + 1]))
    cat = {k: np.concatenate(v) for k, v in out.items()}
    return Path(cat["x"], cat["y"], cat["theta"], cat.get("t"), cat.get("v"))


def turning_angles(path: Path) -> FloatArray:
    """Signed change of the direction of travel at each point (0 at the ends), rad."""
    n = len(path)
    out = np.zeros(n)
    if n < 3:
        return out
    dx, dy = np.diff(path.x), np.diff(path.y)
    valid = np.hypot(dx, dy) > 0
    heading = np.arctan2(dy, dx)
    # a zero-length segment takes the direction of the last real one before it
    for i in range(len(heading)):
        if not valid[i] and i > 0:
            heading[i] = heading[i - 1]
    first = int(np.argmax(valid)) if valid.any() else 0
    heading[:first] = heading[first]
    d = np.diff(heading)
    out[1:-1] = (d + math.pi) % (2 * math.pi) - math.pi
    return out


def curvature(path: Path) -> FloatArray:
    """Signed curvature of the direction of travel at each point, 1/m (left turns positive).

    Discrete: the turning angle at a point divided by the mean length of its two segments, so a
    sharp corner of a finely sampled path has a large but finite curvature.
    """
    n = len(path)
    if n < 3:
        return np.zeros(n)
    ang = turning_angles(path)
    seg = np.diff(path.s)
    mean = np.zeros(n)
    mean[1:-1] = 0.5 * (seg[:-1] + seg[1:])
    out = np.zeros(n)
    ok = mean > 1e-12
    out[ok] = ang[ok] / mean[ok]
    sharp = ~ok & (np.abs(ang) > 0)
    out[sharp] = 1e12 * np.sign(ang[sharp])
    return out


def heading_rate(path: Path) -> FloatArray:
    """d theta / d s at each point, rad/m (central differences; inf where the path turns in place)."""
    n = len(path)
    if n < 2:
        return np.zeros(n)
    ds = np.diff(path.s)
    dth = np.diff(path.theta)
    with np.errstate(divide="ignore", invalid="ignore"):
        seg = np.where(
            ds > 0, dth / np.where(ds > 0, ds, 1.0), np.where(dth != 0, np.inf * np.sign(dth), 0.0)
        )
    out = np.empty(n)
    out[0], out[-1] = seg[0], seg[-1]
    out[1:-1] = 0.5 * (seg[:-1] + seg[1:])
    return out
