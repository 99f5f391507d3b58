"""The idle wheels' roller drag, fitted (pure functions, no I/O; :mod:`omnibot.calibration.rollers`
drives the runs).

Seed 000, section IV: on courses along a motor axis two wheels do not turn, and the friction of
their rollers "depends very much on wheel angle position ... can vary K_l as much as twice". The
controller knows each wheel's angle from its encoder, so it can make up for that drag itself
(:meth:`omnibot.firmware.power.PowerModel.drag`): per wheel, ``cos_i cos(phi_i) + sin_i sin(phi_i)``
PWM counts of the busiest motor, phi_i the roller phase (one period per roller pitch of encoder
counts from the encoders' origin, the controller's power-up) weighted by the wheel's rollers' share
of the travel (:func:`omnibot.firmware.power.roller_terms`). The drag also brakes the coast after the
motors stop, which a MOVE of T s makes up with ``1 + coast(V) / T`` times the drag while it drives.

Fit (:func:`fit_rollers`), least squares over the drag runs j::

    distance_j = e_g + T_j r_g - s (T_j + k_P) D_j,   D_j = sum_i cos_i c_ij + sin_i s_ij

with g the run's course and power (its own start/stop offset e_g and rate r_g), s the slope of the
rate against power (m/s per PWM count), k_P the coast time at power P and c_ij, s_ij the terms of the
wheels that stand still during run j. For given k_P it is linear; the k_P are found by coordinate
search. The drag is kept when it halves the runs' rms scatter and explains them better than its
parameters are worth (the Bayesian information criterion). :func:`correct_runs` then adds the drag
at each axis-course sweep run's own phases back to its distance (``RunResult.correction``), so K_l
on the axes is fitted for the mean drag, which is what the controller's K_l must give once it adds
the rest. The offsets that even the axis courses out (:func:`offset_shift`) are fitted here too, the
coast from MOVEs in :mod:`omnibot.calibration.coastfit`.
"""

from __future__ import annotations

import math
import statistics
from collections import defaultdict
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import NDArray

from omnibot.calibration.patterns import Geometry
from omnibot.calibration.runs import STRAIGHT, RunResult
from omnibot.robot import PiecewiseLinear, RollerDragSpec

GROUP = "rollers"
"""The drag runs' group (:attr:`RunResult.group`)."""
COAST_GRID = tuple(0.02 * k for k in range(151))
"""s: the coast times tried (0..3 s)."""


@dataclass(frozen=True)
class RollerFit:
    """The fitted drag coefficients, the coast table and how much of the runs' scatter they explain."""

    cos: tuple[float, ...]
    sin: tuple[float, ...]
    slope: float
    """m/s of travel per PWM count of the busiest motor, along the axes."""
    speeds: tuple[float, ...]
    """m/s: each power's mean steady speed."""
    coast: tuple[float, ...]
    """s: each power's coast time k_P."""
    runs: int
    rms_before: float
    """m: rms residual of the runs' distances without the drag terms."""
    rms_after: float
    """m: the same with them."""
    kept: bool
    """False when the terms did not explain enough (the spec then holds no drag)."""

    @property
    def coast_table(self) -> PiecewiseLinear:
        """Coast time against speed (m/s), from rest (0 s) through each power's point."""
        return coast_table(zip(self.speeds, self.coast, strict=True))

    @property
    def spec(self) -> RollerDragSpec:
        """The roller drag section for the calibration: the fitted terms when kept, zero drag otherwise."""
        if not self.kept:
            return RollerDragSpec(cos=(0.0,) * len(self.cos), sin=(0.0,) * len(self.sin))
        return RollerDragSpec(cos=self.cos, sin=self.sin, coast=self.coast_table)

    def drag(self, geometry: Geometry, course_deg: float, counts: Sequence[int]) -> float:
        """PWM counts of drag (busiest motor) on a run along the course from these counts, counting
        only the wheels that stand still on it (a turning wheel's drag averages out)."""
        if not self.kept:
            return 0.0
        fc, fs = geometry.roller_terms(course_deg, counts)
        return sum(self.cos[i] * fc[i] + self.sin[i] * fs[i] for i in geometry.idle_wheels(course_deg))

    def as_dict(self) -> dict[str, object]:
        """The fit as plain data (for the JSON report)."""
        return {k: list(v) if isinstance(v, tuple) else v for k, v in self.__dict__.items()}


def coast_table(points: Iterable[tuple[float, float]]) -> PiecewiseLinear:
    """A coast table from (speed m/s, seconds) points: from rest (0 s), speeds rounded to 1 cm/s
    (the CAL resolution; a point no faster than the one before is dropped), times to 1 ms."""
    xs, ys = [0.0], [0.0]
    for v, k in sorted(points):
        if round(v, 2) > xs[-1]:
            xs.append(round(v, 2))
            ys.append(round(k, 3))
    return PiecewiseLinear(x=tuple(xs), y=tuple(ys))


def axis_courses(geometry: Geometry) -> list[float]:
    """Every idle axis and its opposite (degrees, 0..360), round the circle."""
    return sorted({round((a + s) % 360.0, 6) for a in geometry.idle_axes for s in (0.0, 180.0)})


def offset_shift(geometry: Geometry, ahead: Sequence[tuple[float, float, float]]) -> list[float]:
    """PWM counts to add to each motor's dead-band offset so that no course runs ahead of the others.

    ``ahead``: (course, PWM counts of the busiest motor by which a MOVE on it ran ahead of the mean
    of the courses, m of distance per such count). Adding d_i to motor i's offset moves a course
    whose pattern gives motor i the share w_i by ``w . d / w . w`` of the busiest motor. Least
    squares in distance (fast MOVEs, where a count moves little, weigh less), with the offsets' sum
    held (the mean is K_l's) and the minimum-norm split between motors that always drive together;
    motors that drive none of the courses get 0.
    """
    n = geometry.motors
    rows, rhs = [], []
    for course, counts, weight in ahead:
        rims = geometry.translation_rim(course)
        busiest = max(abs(v) for v in rims)
        w = [abs(v) / busiest for v in rims]
        ww = sum(v * v for v in w)
        rows.append([weight * v / ww for v in w])
        rhs.append(-weight * counts)
    if not rows:
        return [0.0] * n
    rows.append([10.0 * max(abs(a[2]) for a in ahead)] * n)
    rhs.append(0.0)
    coef = np.linalg.lstsq(np.asarray(rows), np.asarray(rhs), rcond=None)[0]
    return [round(float(v), 1) for v in coef]


def fit_rollers(geometry: Geometry, runs: Sequence[RunResult]) -> RollerFit | None:
    """Drag coefficients and coast times from :func:`roller_runs` (the module docstring); None when
    the runs cannot tell them (no truth, fewer than two powers, phases that did not spread)."""
    usable = [
        r
        for r in runs
        if r.group == GROUP and r.amount is not None and r.counts is not None and r.power is not None
    ]
    powers = sorted({r.power for r in usable if r.power is not None})
    if len(powers) < 2:
        return None
    n = geometry.motors
    groups, plain, terms, durations, level, b = _drag_system(geometry, usable, powers)
    m, ng = len(usable), len(groups)
    active = [c for c in range(2 * n) if np.any(terms[:, c] != 0.0)]
    if not active:
        return None
    _, cost0 = lstsq(plain, b)
    # wheels whose phases always move together (a mecanum robot's diagonal pair) share their drag:
    # their columns coincide and the minimum-norm solution splits it evenly
    if np.linalg.matrix_rank(plain) < plain.shape[1]:
        return None
    rank = int(np.linalg.matrix_rank(np.hstack((plain, terms[:, active])))) - plain.shape[1]
    if rank == 0 or m <= plain.shape[1] + rank + len(powers):
        return None
    coast, coef, cost = _coast_fit(plain, terms[:, active], durations, level, b, len(powers))
    rates = coef[1 : 2 * ng : 2]
    slope = _rate_slope(groups, rates)
    if slope <= 0.0:
        return None
    drag = np.zeros(2 * n)
    drag[active] = coef[2 * ng :] / slope
    speeds = defaultdict(list)
    for (_, p), rate in zip(groups, rates, strict=True):
        speeds[p].append(float(rate))
    # kept when it halves the runs' rms scatter and passes the Bayesian information criterion on
    # the residuals the groups' own offsets and rates leave (a term that acts on every MOVE should
    # explain something, not fit noise through the coast times' freedom)
    k_params, dof = rank + len(powers), m - 2 * ng
    kept = cost <= 0.25 * cost0 and (
        cost <= 0.0 or dof * math.log(max(cost0, 1e-30) / cost) > k_params * math.log(max(dof, 2))
    )
    return RollerFit(
        cos=tuple(round(float(v), 2) for v in drag[:n]),
        sin=tuple(round(float(v), 2) for v in drag[n:]),
        slope=slope,
        speeds=tuple(statistics.fmean(speeds[p]) for p in powers),
        coast=tuple(coast),
        runs=m,
        rms_before=math.sqrt(cost0 / m),
        rms_after=math.sqrt(cost / m),
        kept=bool(kept),
    )


def _drag_system(
    geometry: Geometry, usable: Sequence[RunResult], powers: Sequence[int]
) -> tuple[
    list[tuple[float, int]],
    NDArray[np.float64],
    NDArray[np.float64],
    NDArray[np.float64],
    NDArray[np.int_],
    NDArray[np.float64],
]:
    """The least-squares system of :func:`fit_rollers`: the (course, power) groups, each run's group
    offset and rate columns, its idle wheels' roller terms, duration, power's index, and distance."""
    n = geometry.motors
    groups = sorted({(r.course_deg or 0.0, r.power or 0) for r in usable})
    g_index = {g: i for i, g in enumerate(groups)}
    p_index = {p: i for i, p in enumerate(powers)}
    m, ng = len(usable), len(groups)
    plain = np.zeros((m, 2 * ng))  # e_g and r_g columns
    terms = np.zeros((m, 2 * n))  # -c_ij, -s_ij of the wheels standing still
    durations = np.zeros(m)
    level = np.zeros(m, dtype=int)
    b = np.zeros(m)
    for j, r in enumerate(usable):
        assert r.counts is not None and r.power is not None and r.amount is not None
        course = r.course_deg or 0.0
        g = g_index[(course, r.power)]
        plain[j, 2 * g] = 1.0
        plain[j, 2 * g + 1] = r.duration
        fc, fs = geometry.roller_terms(course, r.counts[:n])
        for i in geometry.idle_wheels(course):
            terms[j, i], terms[j, n + i] = -fc[i], -fs[i]
        durations[j], level[j], b[j] = r.duration, p_index[r.power], r.amount
    return groups, plain, terms, durations, level, b


def _coast_fit(
    plain: NDArray[np.float64],
    terms: NDArray[np.float64],
    durations: NDArray[np.float64],
    level: NDArray[np.int_],
    b: NDArray[np.float64],
    powers: int,
) -> tuple[list[float], NDArray[np.float64], float]:
    """Each power's coast time (from :data:`COAST_GRID`, by coordinate search) that fits the drag
    ``terms`` best, weighted by each run's duration plus its power's coast: the times, the
    coefficients and the cost."""

    def solve(coast: Sequence[float]) -> tuple[NDArray[np.float64], float]:
        weight = durations + np.asarray(coast)[level]
        return lstsq(np.hstack((plain, terms * weight[:, None])), b)

    coast = [0.0] * powers
    for _ in range(3):
        for q in range(powers):
            trials = [(solve([*coast[:q], k, *coast[q + 1 :]])[1], k) for k in COAST_GRID]
            coast[q] = min(trials)[1]
    coef, cost = solve(coast)
    return coast, coef, cost


def _rate_slope(groups: Sequence[tuple[float, int]], rates: NDArray[np.float64]) -> float:
    """s: the rate's slope against power, common to the courses (each course its own intercept)."""
    courses = sorted({c for c, _ in groups})
    X = np.zeros((len(groups), 1 + len(courses)))
    for g, (c, p) in enumerate(groups):
        X[g, 0], X[g, 1 + courses.index(c)] = p, 1.0
    return float(np.linalg.lstsq(X, rates, rcond=None)[0][0])


def lstsq(A: NDArray[np.float64], b: NDArray[np.float64]) -> tuple[NDArray[np.float64], float]:
    """The least-squares ``x`` of ``A x = b`` and its residual sum of squares."""
    coef = np.asarray(np.linalg.lstsq(A, b, rcond=None)[0], dtype=np.float64)
    residual = b - A @ coef
    return coef, float(residual @ residual)


def correct_runs(geometry: Geometry, fit: RollerFit, runs: Sequence[RunResult]) -> list[RunResult]:
    """The runs with the drag at their own phases added back to the straight ones along an idle
    axis: ``s (T + coast) drag``, the distance they would have covered at the mean drag."""
    out = []
    axes = set(axis_courses(geometry))
    table = fit.coast_table
    for r in runs:
        course = r.course_deg
        if r.kind != STRAIGHT or r.counts is None or course is None or round(course % 360.0, 6) not in axes:
            out.append(r)
            continue
        drag = fit.drag(geometry, course, r.counts[: geometry.motors])
        speed = (r.amount or 0.0) / r.duration if r.duration > 0 else 0.0
        out.append(replace(r, correction=fit.slope * (r.duration + table(speed)) * drag))
    return out
