"""Course folding: the axes K_l's and the reach's courses count from, and tables moved between folds.

The firmware looks K_l (and the calibrated reach) up at the course *folded* onto the robot's
symmetry: the angle from the nearest of its fold axes (mod 180 degrees, mirrored), as
:func:`omnibot.firmware.calibration.fold_course` computes it (:func:`fold` here).

* **Idle axes**: the directions of travel along which some wheel stands still. Seed 000's omni4 has
  them at 0 and 90 degrees and is mirror-symmetric about them and about the diagonals, so every course
  folds onto 0..45; omni3's three axes fold onto 0..30. The roller drag is always about them.
* **Course axes** (K_l's and the reach's): the idle axes on a robot of omni wheels (rollers square to
  the axle, ``gamma`` 0). A mecanum base (rollers at an angle to the axle) is mirror-symmetric about
  its x and y axes only: forward, the diagonals and sideways need different power, so its courses
  fold from the body's x axis onto 0..90 (0 forward, 45 the diagonals, 90 sideways; 135 is 45
  mirrored), not from its idle axes (the diagonals), which would fold forward and sideways together.

A calibration section says which axes its courses count from (``fold_axes_deg``; absent: the idle
axes, as in every file written before the marker). :func:`move_curves` and :func:`move_reach` move
tables made on one set of axes onto another, exactly or not at all (ValueError saying where the
lookups would differ). Plain data only (the description builds its models from them).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable, Sequence

Curve = tuple[tuple[float, ...], tuple[float, ...]]
"""A K_l curve: powers (PWM counts) and factors."""

CURVES_MAX = 8
"""K_l curves the controller holds (the protocol's CAL_KL_CURVES)."""
KNOTS_MAX = 16
"""Knots per table the controller holds (the protocol's CAL_KNOTS_MAX)."""


def fold(course_deg: float, axes: Sequence[float]) -> float:
    """Angle (0..90 degrees) between a course and the nearest of ``axes`` (mod 180): the firmware's
    ``fold_course``."""
    best = 90.0
    for a in axes:
        d = (course_deg - a) % 180.0
        best = min(best, 180.0 - d if d > 90.0 else d)
    return best


def idle_axes(traction_rad: Sequence[float]) -> list[float]:
    """Directions (degrees, 0..180) of travel along which some wheel stands still (its rollers take
    the whole travel): square to each wheel's traction direction (radians)."""
    axes: list[float] = []
    for t in traction_rad:
        a = round((math.degrees(t) + 90.0) % 180.0, 6) % 180.0
        if all(min(abs(a - b), 180.0 - abs(a - b)) > 1e-6 for b in axes):
            axes.append(a)
    return sorted(axes)


def course_axes(traction_rad: Sequence[float], gamma_deg: Sequence[float]) -> list[float]:
    """The axes (degrees) K_l's and the reach's courses fold from: the idle axes for omni wheels,
    the body's x axis (courses 0..90) when any wheel's rollers stand at an angle to its axle."""
    if all(abs(g) < 1e-9 for g in gamma_deg):
        return idle_axes(traction_rad)
    return [0.0]


def fold_max(axes: Sequence[float]) -> float:
    """The largest folded course (degrees): half the widest gap between neighbouring axes (mod 180)."""
    ordered = sorted(a % 180.0 for a in axes)
    if not ordered:
        return 90.0
    gaps = [b - a for a, b in itertools.pairwise(ordered)] + [ordered[0] + 180.0 - ordered[-1]]
    return max(gaps) / 2.0


def same_axes(a: Sequence[float], b: Sequence[float]) -> bool:
    """True when two sets of axes are the same lines (mod 180 degrees)."""
    return sorted({round(v % 180.0, 6) for v in a}) == sorted({round(v % 180.0, 6) for v in b})


def interp(xs: Sequence[float], ys: Sequence[float], x: float) -> float:
    """Piecewise-linear y(x), held constant outside the knots (the firmware's ``interp``)."""
    if x <= xs[0]:
        return ys[0]
    for i in range(1, len(xs)):
        if x <= xs[i]:
            return ys[i - 1] + (x - xs[i - 1]) * (ys[i] - ys[i - 1]) / (xs[i] - xs[i - 1])
    return ys[-1]


def curve_at(courses: Sequence[float], curves: Sequence[Curve], folded: float) -> Curve:
    """K_l's curve at a folded course as the firmware interpolates between ``courses`` (exact: on the
    union of the two neighbours' knots, each held outside its own)."""
    if len(courses) == 1 or folded <= courses[0]:
        return curves[0]
    for i in range(1, len(courses)):
        if folded <= courses[i] + 1e-9:
            if abs(folded - courses[i]) < 1e-9:
                return curves[i]
            (ax, ay), (bx, by) = curves[i - 1], curves[i]
            t = (folded - courses[i - 1]) / (courses[i] - courses[i - 1])
            xs = tuple(sorted(set(ax) | set(bx)))
            ys = tuple(round((1 - t) * interp(ax, ay, x) + t * interp(bx, by, x), 3) for x in xs)
            return xs, ys
    return curves[-1]


def moved_courses(courses: Sequence[float], source: Sequence[float], target: Sequence[float]) -> list[float]:
    """The folded courses on ``target`` where the lookup on ``source`` has a course of its own (a knot)
    or turns (an axis, or halfway between two), within the target's fold range."""
    top = fold_max(source)
    raw = [a + s * c for a in source for c in (*courses, 0.0, top) for s in (1.0, -1.0)]
    raw += [a + s * fold_max(target) for a in target for s in (0.0, 1.0)]
    return sorted({round(fold(r, target), 6) for r in raw})


def move_curves(
    courses: Sequence[float], curves: Sequence[Curve], source: Sequence[float], target: Sequence[float]
) -> tuple[list[float], list[Curve]]:
    """K_l's courses and curves made on the axes ``source`` as curves on the axes ``target`` that give
    the same K_l on every course and power; ValueError when that cannot be done within the
    controller's tables."""
    new = moved_courses(courses, source, target)
    moved = [curve_at(courses, curves, fold(c, source)) for c in new]
    powers = sorted({x for xs, _ in curves for x in xs})

    def old(course: float, p: float) -> float:
        xs, ys = curve_at(courses, curves, fold(course, source))
        return interp(xs, ys, p)

    def now(course: float, p: float) -> float:
        xs, ys = curve_at(new, moved, fold(course, target))
        return interp(xs, ys, p)

    problem = _mismatch(old, now, powers)
    if not problem and (len(new) > CURVES_MAX or any(len(xs) > KNOTS_MAX for xs, _ in moved)):
        problem = f"{len(new)} curves of up to {max(len(xs) for xs, _ in moved)} knots"
    if problem:
        raise ValueError(problem)
    return new, moved


def move_reach(
    courses: Sequence[float], speeds: Sequence[float], source: Sequence[float], target: Sequence[float]
) -> tuple[list[float], list[float]]:
    """The reach table (folded courses, speeds) made on ``source`` as one on ``target``, the same on
    every course; ValueError when it cannot be."""
    new = moved_courses(courses, source, target)
    moved = [round(interp(courses, speeds, fold(c, source)), 6) for c in new]
    problem = _mismatch(
        lambda c, _p: interp(courses, speeds, fold(c, source)),
        lambda c, _p: interp(new, moved, fold(c, target)),
        [0.0],
    )
    if problem:
        raise ValueError(problem)
    return new, moved


def _mismatch(
    old: Callable[[float, float], float], new: Callable[[float, float], float], powers: Sequence[float]
) -> str:
    """Where two lookups (course, power) -> value differ, over every whole degree and the powers
    ('' when nowhere)."""
    for course in range(360):
        for p in powers:
            a, b = old(float(course), p), new(float(course), p)
            if abs(a - b) > 1e-3 * max(1.0, abs(a)):
                return f"course {course} deg at power {p:g}: {a:.4g} against {b:.4g}"
    return ""
