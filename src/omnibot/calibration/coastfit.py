"""The roller drag measured on MOVEs (pure functions, no I/O; :func:`omnibot.calibration.rollers.tune_coast`
drives them): the coast at each speed (how much longer than the MOVE the drag acts, and how far each
course ran ahead) and each idle wheel's drag as the MOVEs themselves measured it."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from omnibot.calibration.patterns import Geometry
from omnibot.calibration.rollerfit import coast_table, lstsq
from omnibot.robot import PiecewiseLinear, RollerDragSpec


@dataclass(frozen=True)
class CoastTuning:
    """What :func:`tune_coast` measured at each speed and the coast table it gives."""

    speeds: tuple[float, ...]
    """m/s of the MOVEs."""
    drag: tuple[float, ...]
    """m of distance lost per PWM count of drag, without the term (lambda)."""
    power: tuple[float, ...]
    """m of distance gained per PWM count the term adds (mu)."""
    gains: tuple[float, ...]
    """The drag gain each speed needs, ``lambda / mu`` (the controller's ``1 + coast / T``)."""
    table: PiecewiseLinear
    runs: int
    ahead: tuple[tuple[float, float, float], ...] = ()
    """(course, PWM counts, m per count): how far each course's MOVEs ran ahead of the mean of the
    courses at the same speed, in power, and mu (:func:`offset_shift` evens it out)."""
    cos: tuple[float, ...] | None = None
    sin: tuple[float, ...] | None = None
    """Each wheel's drag coefficients as the slowest speed's MOVEs measured them (:func:`fit_idle_drag`;
    they replace the drag runs' own), None where those MOVEs could not tell them."""

    def as_dict(self) -> dict[str, object]:
        """The fit as plain data (for the JSON report)."""
        out: dict[str, object] = {k: list(v) for k, v in self.__dict__.items() if isinstance(v, tuple)}
        out["table"] = {"x": list(self.table.x), "y": list(self.table.y)}
        out["runs"] = self.runs
        return out


def coast_row(courses: Sequence[float], course: float, drag: float, gain: float) -> list[float]:
    """One MOVE's row of :func:`fit_coast_speed`: its course's offset, ``-D`` and ``g D``."""
    return [1.0 if c == course else 0.0 for c in courses] + [-drag, gain * drag]


def fit_coast_speed(
    courses: Sequence[float], rows: Sequence[Sequence[float]], distances: Sequence[float]
) -> tuple[float, float, list[tuple[float, float, float]]] | None:
    """(lambda, mu, ahead) of one speed's MOVEs (:func:`omnibot.calibration.rollers.tune_coast`):
    ``distance_j = e_course - lambda D_j + mu g_j D_j`` by least squares, and how far each course
    ran ahead of the mean of the courses (course, PWM counts, mu); None when the runs cannot tell."""
    unknowns = len(courses) + 2
    if len(distances) <= unknowns or np.linalg.matrix_rank(np.asarray(rows)) < unknowns:
        return None
    coef, _ = lstsq(np.asarray(rows), np.asarray(distances))
    lam, mu = float(coef[-2]), float(coef[-1])
    if mu <= 0.0 or lam <= 0.0:
        return None
    offsets = coef[: len(courses)]
    mean = float(np.mean(offsets))
    return lam, mu, [(c, (float(e) - mean) / mu, mu) for c, e in zip(courses, offsets, strict=True)]


def coast_tuning(
    found: Sequence[tuple[float, float, float, float]],
    ahead: Sequence[tuple[float, float, float]],
    runs: int,
    length: float,
    idle: IdleDrag | None = None,
) -> CoastTuning:
    """The :class:`CoastTuning` of each speed's (speed, lambda, mu, gain) and the courses' lead, with
    the drag coefficients ``idle`` the MOVEs measured (if any)."""
    return CoastTuning(
        speeds=tuple(f[0] for f in found),
        drag=tuple(f[1] for f in found),
        power=tuple(f[2] for f in found),
        gains=tuple(f[3] for f in found),
        table=coast_table((speed, (g - 1.0) * length / speed) for speed, _, _, g in found),
        runs=runs,
        ahead=tuple(ahead),
        cos=None if idle is None else idle.cos,
        sin=None if idle is None else idle.sin,
    )


@dataclass(frozen=True)
class IdleDrag:
    """The idle wheels' drag as MOVEs measured it (:func:`fit_idle_drag`)."""

    cos: tuple[float, ...]
    sin: tuple[float, ...]
    """PWM counts per wheel (the controller's term: ``cos_i cos(phi_i) + sin_i sin(phi_i)``)."""
    power: float
    """m of distance gained per PWM count the term adds (mu)."""
    ahead: list[tuple[float, float, float]]
    """(course, PWM counts, mu): how far each course ran ahead of the mean of the courses."""


def idle_row(
    geometry: Geometry, courses: Sequence[float], course: float, counts: Sequence[int], term: float
) -> list[float]:
    """One MOVE's row of :func:`fit_idle_drag`: its course's offset, the roller terms ``c_i, s_i`` of
    every wheel standing still on it (0 for the others), and the PWM counts ``term`` the controller
    added for the drag."""
    n = geometry.motors
    fc, fs = geometry.roller_terms(course, counts[:n])
    cs = [0.0] * (2 * n)
    for i in geometry.idle_wheels(course):
        cs[i], cs[n + i] = fc[i], fs[i]
    return [1.0 if c == course else 0.0 for c in courses] + cs + [term]


def fit_idle_drag(
    geometry: Geometry, courses: Sequence[float], rows: Sequence[Sequence[float]], distances: Sequence[float]
) -> IdleDrag | None:
    """Each idle wheel's drag from MOVEs at one speed (:func:`idle_row` each), by least squares::

        distance_j = e_course + sum_i (a_i c_ij + b_i s_ij) + mu T_j

    ``a_i, b_i``: the distance the wheel's drag takes at its phase, ``mu``: the distance a PWM count
    of the term gives back (T_j: the counts the controller added, 0 in MOVEs without the term). The
    term that cancels the drag is ``cos_i = -a_i / mu``, ``sin_i = -b_i / mu``. Measured on the
    MOVEs themselves, so it holds the drag's whole effect at that speed (the start, the steady
    speed and the coast). Wheels whose terms always move together share (minimum norm). None when
    the MOVEs cannot tell mu or the drag (too few, no term, phases that did not spread)."""
    A, b = np.asarray(rows, dtype=float), np.asarray(distances, dtype=float)
    nc, n = len(courses), geometry.motors
    if A.ndim != 2 or A.shape[0] == 0:
        return None
    active = [c for c in range(nc, nc + 2 * n) if np.any(A[:, c] != 0.0)]
    if not active:
        return None
    cols = list(range(nc)) + active + [A.shape[1] - 1]
    X = A[:, cols]
    rank = int(np.linalg.matrix_rank(X))
    # the offsets and mu must be told apart from the drag (a rank short of them: no answer)
    if rank < nc + 1 or int(np.linalg.matrix_rank(X[:, :-1])) == rank or len(b) <= rank + 1:
        return None
    coef, _ = lstsq(X, b)
    mu = float(coef[-1])
    if mu <= 0.0:
        return None
    drag = np.zeros(2 * n)
    drag[[c - nc for c in active]] = -coef[nc:-1] / mu
    offsets = coef[:nc]
    mean = float(np.mean(offsets))
    return IdleDrag(
        cos=tuple(round(float(v), 2) for v in drag[:n]),
        sin=tuple(round(float(v), 2) for v in drag[n:]),
        power=mu,
        ahead=[(c, (float(e) - mean) / mu, mu) for c, e in zip(courses, offsets, strict=True)],
    )


def spec_drag(geometry: Geometry, rollers: RollerDragSpec, course: float, counts: Sequence[int]) -> float:
    """PWM counts of drag the controller adds with ``rollers`` on a MOVE along the course from these
    counts (before the coast's gain; :meth:`omnibot.firmware.power.PowerModel.drag`)."""
    fc, fs = geometry.roller_terms(course, counts[: geometry.motors])
    return sum(c * a + s * b for c, s, a, b in zip(rollers.cos, rollers.sin, fc, fs, strict=True))
