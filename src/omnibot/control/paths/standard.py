"""Standard test paths: line, circle, figure eight, S curve, square with sharp corners, lemniscate.

Every path starts at the origin heading along +x, is scaled by ``size`` (m) and sampled every
``spacing`` m of arc length. ``heading`` picks the theta column: ``"fixed"`` holds the start heading
(what an omnidirectional robot can do, and what seed 002 does), ``"tangent"`` turns the body with
the direction of travel, ``"swing"`` swings it independently of the course, 90 degrees either side
of the start heading, one period every 2 ``size`` m of travel (theta = pi/2 sin(pi s / size)).

====================  ============================================================================
name                  shape (size s)
====================  ============================================================================
``line``              2 s straight ahead
``circle``            one counter-clockwise lap of radius s/2
``figure_eight``      two tangent circles of radius s/2: left lap, then right lap (curvature flips)
``s_curve``           two half circles of radius s/2, left then right: seed 002's S path
``square``            side s, counter-clockwise, four sharp 90 degree corners
``lemniscate``        Bernoulli's lemniscate, half-width s (smooth figure eight)
====================  ============================================================================
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from omnibot.control.paths.geometry import resample
from omnibot.control.paths.path import FloatArray, Path, tangent_headings
from omnibot.errors import ConfigError

HEADINGS = ("fixed", "tangent", "swing")
SWING = 0.5 * math.pi
"""rad: the amplitude of the ``swing`` heading."""


def _arc(cx: float, cy: float, r: float, a0: float, a1: float, n: int) -> FloatArray:
    a = np.linspace(a0, a1, n)
    return np.column_stack((cx + r * np.cos(a), cy + r * np.sin(a)))


def _line(size: float) -> FloatArray:
    return np.array([(0.0, 0.0), (2.0 * size, 0.0)])


def _circle(size: float) -> FloatArray:
    r = size / 2
    return _arc(0.0, r, r, -math.pi / 2, 1.5 * math.pi, 2000)


def _figure_eight(size: float) -> FloatArray:
    r = size / 2
    top = _arc(0.0, r, r, -math.pi / 2, 1.5 * math.pi, 2000)
    bottom = _arc(0.0, -r, r, math.pi / 2, -1.5 * math.pi, 2000)
    return np.vstack((top, bottom[1:]))


def _s_curve(size: float) -> FloatArray:
    r = size / 2
    first = _arc(0.0, r, r, -math.pi / 2, math.pi / 2, 1000)
    second = _arc(0.0, 3 * r, r, -math.pi / 2, -1.5 * math.pi, 1000)
    return np.vstack((first, second[1:]))


def _square(size: float) -> FloatArray:
    return np.array([(0.0, 0.0), (size, 0.0), (size, size), (0.0, size), (0.0, 0.0)])


def _lemniscate(size: float) -> FloatArray:
    t = np.linspace(math.pi / 2, 2.5 * math.pi, 4000)
    d = 1.0 + np.sin(t) ** 2
    x, y = size * np.cos(t) / d, size * np.sin(t) * np.cos(t) / d
    rot = 0.75 * math.pi  # start heading along +x
    c, s = math.cos(rot), math.sin(rot)
    return np.column_stack((c * x - s * y, s * x + c * y))


SHAPES: dict[str, Callable[[float], FloatArray]] = {
    "line": _line,
    "circle": _circle,
    "figure_eight": _figure_eight,
    "s_curve": _s_curve,
    "square": _square,
    "lemniscate": _lemniscate,
}


def standard_names() -> list[str]:
    """The names of the standard paths (see the module docstring)."""
    return list(SHAPES)


def standard_path(name: str, size: float = 1.0, heading: str = "fixed", spacing: float = 0.01) -> Path:
    """The standard path ``name`` (see the module docstring)."""
    try:
        shape = SHAPES[name]
    except KeyError:
        import difflib

        close = difflib.get_close_matches(name, list(SHAPES), n=1, cutoff=0.5)
        hint = f"; did you mean '{close[0]}'?" if close else f"; expected one of: {', '.join(SHAPES)}"
        raise ConfigError(f"unknown path '{name}'" + hint) from None
    if heading not in HEADINGS:
        raise ConfigError(f"unknown heading mode '{heading}'; expected fixed, tangent or swing")
    if not size > 0:
        raise ConfigError(f"path size must be positive, got {size}")
    pts = shape(size)
    dense = resample(Path.from_points(pts, theta=0.0), spacing)
    return _with_heading(dense, heading, size)


def _with_heading(path: Path, heading: str, size: float = 1.0) -> Path:
    if heading == "fixed":
        return path.with_columns(theta=np.zeros(len(path)))
    if heading == "swing":
        return path.with_columns(theta=SWING * np.sin(math.pi * path.s / size))
    th = tangent_headings(path.x, path.y)
    th = th - (th[0] - math.atan2(path.y[1] - path.y[0], path.x[1] - path.x[0]))
    return path.with_columns(theta=th)


def random_path(
    length: float, *, seed: int = 0, size: float = 1.0, heading: str = "mixed", spacing: float = 0.01
) -> Path:
    """A smooth pseudo-random drive of about ``length`` m: straights and arcs of radius size/2..2 size.

    ``heading``: ``fixed``, ``tangent``, ``swing`` or ``mixed`` (the body turns with the path plus a slow
    sideways swing of +-45 degrees, so the drive exercises translation and rotation together).
    """
    rng = np.random.default_rng(seed)
    pts = [(0.0, 0.0)]
    x = y = direction = 0.0
    travelled = 0.0
    while travelled < length:
        straight = float(rng.uniform(0.5, 2.0) * size)
        n = max(2, int(straight / 0.01))
        for k in range(1, n + 1):
            pts.append(
                (x + math.cos(direction) * straight * k / n, y + math.sin(direction) * straight * k / n)
            )
        x, y = pts[-1]
        travelled += straight
        radius = float(rng.uniform(0.5, 2.0) * size)
        turn = float(rng.uniform(0.5, 2.5)) * (1 if rng.random() < 0.5 else -1)
        cx, cy = (
            x - math.sin(direction) * radius * math.copysign(1, turn),
            y + math.cos(direction) * radius * math.copysign(1, turn),
        )
        a0 = math.atan2(y - cy, x - cx)
        arc = _arc(cx, cy, radius, a0, a0 + turn, max(3, int(abs(turn) * radius / 0.01)))
        pts.extend((float(px), float(py)) for px, py in arc[1:])
        x, y = pts[-1]
        direction += turn
        travelled += abs(turn) * radius
    dense = resample(Path.from_points(np.array(pts), theta=0.0), spacing)
    if heading == "mixed":
        base = _with_heading(dense, "tangent")
        swing = 0.25 * math.pi * np.sin(2 * math.pi * dense.s / (7.0 * size))
        return base.with_columns(theta=base.theta + swing)
    if heading not in HEADINGS:
        raise ConfigError(f"unknown heading mode '{heading}'; expected fixed, tangent, swing or mixed")
    return _with_heading(dense, heading, size)
