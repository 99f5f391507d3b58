"""Wheel radius and wheel base corrections for odometry: a rotation test and a UMBmark-style square.

Borenstein and Feng's UMBmark drives a square clockwise and counter-clockwise and reads the two
systematic odometry errors of a differential robot from the return errors. Adapted here to any
omni or mecanum robot (the derivation is in docs/calibration.md):

* wheel radius scale ``s_r`` = true distance / odometry distance over the straight runs (all wheel
  radii scaled alike: what a worn or different tyre does);
* rotation scale ``s_w`` = true angle / odometry angle over the rotation test (turns each way);
  odometry's rotation is ``r / R`` times the wheel angles, so the wheel base scale (the wheels'
  distance from the centre, R_c for omni4) is ``s_b = s_r / s_w``;
* the square (legs on course 0, +-90 degree ROTATEs at the corners): with ``e`` the true end point
  minus the odometry end point in the start frame, the linearised errors are::

        e_ccw = 2 L (A + B) (1, -1),   e_cw = 2 L (A - B) (1, 1)

  where ``A = (pi / 2) eps_w`` is the corner error of a rotation scale 1 + eps_w and ``B`` the body
  turn odometry misses on each leg (the omni analogue of UMBmark's unequal wheel diameters); the
  distance scale and a constant course offset cancel round a closed square. So
  ``A = (e_ccw.x + e_cw.x) / 4L = (e_cw.y - e_ccw.y) / 4L`` and
  ``B = (e_ccw.x - e_cw.x) / 4L = -(e_ccw.y + e_cw.y) / 4L`` (each the mean of both forms).
"""

from __future__ import annotations

import math
import statistics
from collections.abc import Sequence
from dataclasses import asdict, dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from omnibot.calibration.runs import STRAIGHT, Motion, RunResult
from omnibot.estimation import compose_arc
from omnibot.motion import Pose2D
from omnibot.robot import RobotDescription, parse_description

if TYPE_CHECKING:  # the samples' type only: the square runs are driven by experiments.drive_square
    from omnibot.client import Telemetry


@dataclass
class SquareRun:
    """One UMBmark square: its direction, side (m), the run's measurement and its telemetry."""

    ccw: bool
    side: float
    result: RunResult
    log: list[Telemetry] = field(default_factory=list)

    @property
    def error(self) -> tuple[float, float] | None:
        """True end minus odometry end (m), in the start frame."""
        t, o = self.result.truth, self.result.odometry
        if t is None or o is None or t.x is None or t.y is None or o.x is None or o.y is None:
            return None
        return (t.x - o.x, t.y - o.y)


@dataclass(frozen=True)
class UmbResult:
    """UMBmark's two numbers from a CCW and a CW square."""

    corner_error: float
    """A: rad of extra turn per corner (rotation scale error times pi / 2)."""
    leg_turn: float
    """B: rad the body turns on each leg that odometry does not see."""
    rotation_scale: float
    """1 + 2 A / pi."""
    error_ccw: tuple[float, float]
    error_cw: tuple[float, float]


def umbmark(ccw: tuple[float, float], cw: tuple[float, float], side: float) -> UmbResult:
    """A and B from the return errors (true minus odometry end, m) of both squares."""
    a = 0.5 * ((ccw[0] + cw[0]) + (cw[1] - ccw[1])) / (4 * side)
    b = 0.5 * ((ccw[0] - cw[0]) - (ccw[1] + cw[1])) / (4 * side)
    return UmbResult(a, b, 1.0 + 2.0 * a / math.pi, ccw, cw)


@dataclass(frozen=True)
class OdometryCalibration:
    """Correction factors for wheel odometry (apply with :func:`corrected_robot`)."""

    wheel_radius_scale: float
    """true / odometry distance of the straight runs."""
    wheel_base_scale: float
    """wheel radius scale / rotation scale."""
    rotation_scale: float
    """true / odometry angle of the rotation test."""
    square_rotation_scale: float | None = None
    """The rotation scale fitted to the squares' end poses, a cross-check."""
    leg_drift_deg_per_m: float | None = None
    """Body turn odometry does not see while translating (UMBmark's type B error), per metre."""
    umbmark_corner_deg: float | None = None
    umbmark_leg_deg: float | None = None
    """Classic UMBmark's A and B (ideal-square linearisation of the two return errors), degrees."""
    return_error_before: float | None = None
    """Mean over both squares of |true - odometry end| with the description's geometry, m."""
    return_error_after: float | None = None
    """The same with the corrected radius and base."""
    return_error_drift: float | None = None
    """The same with the drift removed too (odometry that models it)."""
    straight_runs: int = 0
    rotation_runs: int = 0

    def as_dict(self) -> dict[str, Any]:
        """The result as plain data (for the calibration file), unset fields left out."""
        return {k: v for k, v in asdict(self).items() if v is not None}


def ratio(pairs: Sequence[tuple[float, float]]) -> float | None:
    """Median of truth / odometry over pairs (truth, odometry) with a usable odometry value."""
    values = [t / o for t, o in pairs if abs(o) > 1e-3]
    return statistics.median(values) if values else None


def distance_pairs(runs: Sequence[RunResult], minimum: float = 0.1) -> list[tuple[float, float]]:
    """(truth, odometry) path lengths of the straight runs measured both ways, the true one at least
    ``minimum`` m."""
    out = []
    for r in runs:
        if r.kind != STRAIGHT or r.truth is None or r.odometry is None:
            continue
        t, o = r.truth.path, r.odometry.path
        if t is not None and o is not None and t >= minimum:
            out.append((t, o))
    return out


def angle_pairs(runs: Sequence[RunResult]) -> list[tuple[float, float]]:
    """(truth, odometry) heading changes of the runs measured both ways, rad."""
    out = []
    for r in runs:
        if r.truth is None or r.odometry is None or r.truth.theta is None or r.odometry.theta is None:
            continue
        out.append((r.truth.theta, r.odometry.theta))
    return out


def corrected_robot(robot: RobotDescription, radius_scale: float, base_scale: float) -> RobotDescription:
    """The description with every wheel radius times ``radius_scale`` and every wheel's distance
    from the centre times ``base_scale`` (for odometry; the power calibration stays as fitted)."""
    data = robot.model_dump(exclude_none=True)
    for w in data["wheels"]:
        w["radius"] *= radius_scale
        for key in ("x", "y", "L"):
            if key in w:
                w[key] *= base_scale
    return parse_description(data, f"{robot.name} (odometry corrected)")


# --------------------------------------------------------------------------- squares on the real path

Increment = tuple[float, float, float]


def increments(robot: RobotDescription, log: Sequence[Telemetry]) -> list[Increment]:
    """Body-frame odometry increments (dx, dy, dtheta) between consecutive TEL samples."""
    if not robot.has_wheel_encoders:
        return []
    cpr = {e.wheel: e.counts_per_rev for e in robot.encoders.motors}
    rad = np.array([2.0 * math.pi / cpr[w.name] for w in robot.wheels])
    pinv = np.array(robot.forward_rows)  # the robot's one least-squares inverse of J (3, n)
    out: list[Increment] = []
    last = None
    for tel in log:
        if tel.encoders is None:
            continue
        c = np.asarray(tel.encoders, dtype=float)
        if last is not None:
            dx, dy, dth = (float(v) for v in pinv @ ((c - last) * rad))
            out.append((dx, dy, dth))
        last = c
    return out


def integrate(
    incs: Sequence[Increment], radius: float = 1.0, rotation: float = 1.0, drift: float = 0.0
) -> Pose2D:
    """The end pose (start frame) of odometry increments with translation times ``radius``,
    rotation times ``rotation`` plus ``drift`` rad per metre travelled."""
    pose = Pose2D(0.0, 0.0, 0.0)
    for dx, dy, dth in incs:
        tx, ty = radius * dx, radius * dy
        pose = compose_arc(pose, tx, ty, rotation * dth + drift * math.hypot(tx, ty))
    return pose


def fit_squares(
    paths: Sequence[tuple[Sequence[Increment], Motion]], radius: float, rotation: float, side: float
) -> tuple[float, float] | None:
    """(rotation scale, drift rad/m) that carry the squares' odometry onto their true end poses, the
    wheel radius scale given (a closed square hides it): Gauss-Newton on the end x, y and (weighted
    by the side) heading of every square, started at ``rotation``. For an ideal square it reduces to
    UMBmark's closed form (:func:`umbmark`)."""
    usable = [(incs, m) for incs, m in paths if incs and m.x is not None and m.y is not None]
    if len(usable) < 2:
        return None

    def residuals(p: np.ndarray) -> np.ndarray:
        out = []
        for incs, m in usable:
            end = integrate(incs, radius, float(p[0]), float(p[1]))
            assert m.x is not None and m.y is not None
            out += [end.x - m.x, end.y - m.y]
            if m.theta is not None:
                out.append(side * (end.theta - m.theta))
        return np.array(out)

    p = np.array([rotation, 0.0])
    for _ in range(12):
        r0 = residuals(p)
        jac = np.empty((r0.size, 2))
        for k in range(2):
            dp = np.zeros(2)
            dp[k] = 1e-6
            jac[:, k] = (residuals(p + dp) - r0) / 1e-6
        step, *_ = np.linalg.lstsq(jac, -r0, rcond=None)
        p = p + step
        if float(np.max(np.abs(step))) < 1e-8:
            break
    if not np.all(np.isfinite(p)) or p[0] <= 0:
        return None
    return float(p[0]), float(p[1])


def calibrate_odometry(
    robot: RobotDescription,
    straight: Sequence[RunResult],
    rotations: Sequence[RunResult],
    squares: Sequence[SquareRun],
) -> OdometryCalibration | None:
    """Correction factors from straight runs, the rotation test and the squares (None if unusable)."""
    d_pairs = distance_pairs(straight)
    a_pairs = angle_pairs(rotations)
    s_r, s_w = ratio(d_pairs), ratio(a_pairs)
    if s_r is None or s_w is None:
        return None
    extra: dict[str, float] = {}
    by_dir = {sq.ccw: sq for sq in squares if sq.error is not None and sq.result.truth is not None}
    if True in by_dir and False in by_dir:
        side = by_dir[True].side
        e_ccw, e_cw = by_dir[True].error, by_dir[False].error
        assert e_ccw is not None and e_cw is not None
        umb = umbmark(e_ccw, e_cw, side)
        extra["umbmark_corner_deg"] = round(math.degrees(umb.corner_error), 3)
        extra["umbmark_leg_deg"] = round(math.degrees(umb.leg_turn), 3)
        paths = [(increments(robot, sq.log), sq.result.truth) for sq in by_dir.values()]
        truths = [m for _, m in paths if m is not None]

        def miss(radius: float, rotation: float, drift: float) -> float:
            errs = []
            for incs, m in paths:
                assert m is not None and m.x is not None and m.y is not None
                end = integrate(incs, radius, rotation, drift)
                errs.append(math.hypot(end.x - m.x, end.y - m.y))
            return round(statistics.fmean(errs), 4)

        if all(m.x is not None and m.y is not None for m in truths):
            extra["return_error_before"] = miss(1.0, 1.0, 0.0)
            extra["return_error_after"] = miss(s_r, s_w, 0.0)
            fitted = fit_squares([(i, m) for i, m in paths if m is not None], s_r, s_w, side)
            if fitted is not None:
                extra["square_rotation_scale"] = round(fitted[0], 4)
                extra["leg_drift_deg_per_m"] = round(math.degrees(fitted[1]), 3)
                extra["return_error_drift"] = miss(s_r, s_w, fitted[1])
    return OdometryCalibration(
        wheel_radius_scale=round(s_r, 4),
        wheel_base_scale=round(s_r / s_w, 4),
        rotation_scale=round(s_w, 4),
        straight_runs=len(d_pairs),
        rotation_runs=len(a_pairs),
        **extra,
    )
