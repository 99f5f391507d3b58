"""Time-optimal speed along a path under speed, acceleration and traction limits (forward-backward).

The path is walked in a generalised arc length sigma, d sigma = sqrt(ds^2 + (rho d theta)^2), so a
turn in place (ds = 0) is a stretch of path like any other. With u = d sigma / dt the robot's speed
is v = u ds/d sigma and its turn rate w = u d theta/d sigma. At each point of a fine grid:

* speed caps: v <= v_max, |w| <= w_max, v^2 |kappa| <= a_lat (the wheels' grip sideways),
  v^2 |d^2 theta/ds^2| <= alpha_max / 2, v <= the path file's v when it has one, and, when the
  limits carry the robot's wheel rows (:mod:`omnibot.control.reach`), no wheel faster than
  ``wheel_use`` of its free-running speed for the body twist there: translation along the course
  as seen from the body (the path's direction turned by -theta) and the turn rate together, so a
  body turning while it goes, or a course the wheels serve badly, slows the profile; and, when
  they carry a floor's reach (``MotionLimits.from_robot(..., surface=...)``), the body twist
  (translation along its body course and the turn together) no larger than ``floor_use`` of what
  the floor's load leaves the motors; and, when they carry a ``course_rate``, v |kappa| no larger
  than it (the wheels' sideways creep in a turn, which the odometry does not see;
  :func:`profile_within` keeps that cap only within a time budget);
* acceleration: the tangential acceleration may use what the lateral one leaves of the friction
  ellipse, a_t <= a_max sqrt(1 - (v^2 kappa / a_lat)^2), and the angular one alpha_max / 2; on a
  floor (``grip``) all of them, and the lateral and heading caps, times the fraction the wheels'
  grip leaves beside the floor's drag at that speed.

A forward pass from rest accelerates as hard as allowed, a backward pass from rest at the end
brakes as late as allowed, and the smaller of the two (and the caps) is the time-optimal profile of
this point-mass-plus-rotation model (the classical result for one path parameter). Its duration is
the minimum traversal time: no follower can be faster within those limits, which is what makes it
the yardstick of the benchmarks. Followers may plan with a margin (limits scaled below 1) to keep
authority for feedback.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from omnibot.control.paths.geometry import curvature, heading_rate
from omnibot.control.paths.limits import MotionLimits
from omnibot.control.paths.path import FloatArray, Path
from omnibot.errors import ConfigError

RHO = 0.1
"""m: the length a radian of turning in place counts for in sigma (only the grid depends on it)."""
MAX_SAMPLES = 200_000
"""Grid points a profile may have (2 km of path at the default 1 cm; about 100 MB while built)."""


@dataclass(frozen=True)
class Reference:
    """Where the profile is at one time: pose, world velocity and acceleration, arc length."""

    t: float
    s: float
    x: float
    y: float
    theta: float
    vx: float
    vy: float
    w: float
    ax: float
    ay: float
    speed: float
    alpha: float = 0.0
    """The heading's angular acceleration, rad/s^2 (within the segment: the turn rate u theta' changes
    with the pace u only)."""


@dataclass(frozen=True, eq=False)
class SpeedProfile:
    """A time-optimal profile on a fine grid (arrays of equal length, one entry per grid point)."""

    t: FloatArray
    s: FloatArray
    sigma: FloatArray
    x: FloatArray
    y: FloatArray
    theta: FloatArray
    u: FloatArray
    """d sigma / dt at each point."""
    rs: FloatArray
    """ds / d sigma of the segment starting at each point (last: copy of the one before)."""
    rt: FloatArray
    """d theta / d sigma of the segment starting at each point."""
    tx: FloatArray
    ty: FloatArray
    """Direction of travel of the segment starting at each point."""
    kappa: FloatArray

    @property
    def min_time(self) -> float:
        """Duration of the profile, s (the minimum traversal time when planned at the robot's limits)."""
        return float(self.t[-1])

    @property
    def speed(self) -> FloatArray:
        """Translational speed at each grid point, m/s."""
        prev = np.concatenate(([self.rs[0]], self.rs[:-1]))
        return self.u * np.maximum(self.rs, prev)

    def speed_at(self, s: float) -> float:
        """Translational speed at arc length ``s`` (the larger where a turn in place sits)."""
        return float(np.interp(s, self.s, self.speed))

    def at(self, t: float) -> Reference:
        """The reference at time ``t`` (clamped to the profile), constant acceleration per segment."""
        n = len(self.t)
        tc = min(max(t, 0.0), float(self.t[-1]))
        j = int(np.searchsorted(self.t, tc, side="right")) - 1
        j = min(max(j, 0), n - 2)
        dt = float(self.t[j + 1] - self.t[j])
        dsig = float(self.sigma[j + 1] - self.sigma[j])
        u0, u1 = float(self.u[j]), float(self.u[j + 1])
        tau = tc - float(self.t[j])
        acc = (u1 - u0) / dt if dt > 0 else 0.0
        progress = u0 * tau + 0.5 * acc * tau * tau
        f = min(max(progress / dsig, 0.0), 1.0) if dsig > 0 else 0.0
        u = u0 + acc * tau
        rs, rt = float(self.rs[j]), float(self.rt[j])
        tx, ty = float(self.tx[j]), float(self.ty[j])
        v = u * rs
        a_t = acc * rs
        k = float(self.kappa[j] + f * (self.kappa[j + 1] - self.kappa[j]))
        a_n = v * v * k
        return Reference(
            t=tc,
            s=float(self.s[j] + f * (self.s[j + 1] - self.s[j])),
            x=float(self.x[j] + f * (self.x[j + 1] - self.x[j])),
            y=float(self.y[j] + f * (self.y[j + 1] - self.y[j])),
            theta=float(self.theta[j] + f * (self.theta[j + 1] - self.theta[j])),
            vx=v * tx,
            vy=v * ty,
            w=u * rt,
            ax=a_t * tx - a_n * ty,
            ay=a_t * ty + a_n * tx,
            speed=v,
            alpha=acc * rt,
        )


def _check_size(path: Path, resolution: float) -> None:
    """Refuse a path whose grid would exceed :data:`MAX_SAMPLES` (before a byte of it is built)."""
    if not (math.isfinite(resolution) and resolution > 0):
        raise ValueError(f"a speed profile needs a positive resolution, got {resolution}")
    with np.errstate(over="ignore", invalid="ignore"):
        seg = np.hypot(np.diff(path.s), RHO * np.diff(path.theta))
        if not np.all(np.isfinite(seg)):
            raise ConfigError("the path has points too far out to profile (its length is not finite)")
        steps = float(np.sum(np.where(seg > 1e-12, np.maximum(1.0, np.ceil(seg / resolution - 1e-9)), 0.0)))
    if steps > MAX_SAMPLES:
        raise ConfigError(
            f"the path is too long to profile: {float(np.sum(seg)):.4g} m of travel (turning included) "
            f"needs {steps:.3g} steps of {resolution:g} m, at most {MAX_SAMPLES:,}; split it"
        )


def time_optimal_profile(
    path: Path, limits: MotionLimits, *, resolution: float = 0.01, use_path_speed: bool = True
) -> SpeedProfile:
    """The time-optimal profile of ``path`` under ``limits`` (see the module docstring).

    ``resolution`` is the grid step in sigma (m); ``use_path_speed`` caps the speed by the path's
    v column when it has one. A path that would need more than :data:`MAX_SAMPLES` grid points
    raises :class:`~omnibot.errors.ConfigError` (bounded memory, whatever the path).
    """
    if len(path) < 2:
        raise ValueError("a speed profile needs a path of at least two points")
    _check_size(path, resolution)
    grid = _refine(path, resolution, use_path_speed)
    S = np.array(grid.sigma)
    rs = np.array(grid.rs)
    rt = np.abs(np.array(grid.rt))
    rs_pt = np.maximum(rs, np.concatenate(([rs[0]], rs[:-1])))
    rt_pt = np.maximum(rt, np.concatenate(([rt[0]], rt[:-1])))
    K = np.abs(np.array(grid.kappa))
    cap = _speed_cap(limits, grid, rs, rs_pt, rt_pt, K)
    accel = _accel_limit(limits, rs_pt, rt_pt, K)
    dsig = np.diff(S)
    u = _forward_backward(cap, dsig, accel)
    return SpeedProfile(
        t=_times(u, dsig, accel),
        s=np.array(grid.s),
        sigma=S,
        x=np.array(grid.x),
        y=np.array(grid.y),
        theta=np.array(grid.theta),
        u=u,
        rs=rs,
        rt=np.array(grid.rt),
        tx=np.array(grid.tx),
        ty=np.array(grid.ty),
        kappa=np.array(grid.kappa),
    )


@dataclass
class _Grid:
    """The path refined into steps of at most the resolution in sigma: one entry per grid point."""

    x: list[float]
    y: list[float]
    theta: list[float]
    """The pose, interpolated along each segment."""
    s: list[float]
    sigma: list[float]
    """Arc length and generalised arc length (m)."""
    kappa: list[float]
    hcurv: list[float]
    vfile: list[float]
    """The curvature of travel, the heading's curvature and the file's speed (inf: none), interpolated."""
    rs: list[float]
    rt: list[float]
    """ds/dsigma and dtheta/dsigma of the step from the point (the last point repeats the last step's)."""
    tx: list[float]
    ty: list[float]
    """The direction of travel of that step (of the last one that moved when it only turns)."""


def _point_curvatures(path: Path) -> tuple[FloatArray, FloatArray]:
    """Per original point: the curvature of travel (signed, left positive) and the heading's
    curvature |d^2 theta/ds^2| (central differences; 0 at the ends)."""
    hr = heading_rate(path)
    hr_f = np.where(np.isfinite(hr), hr, 0.0)
    hcurv0 = np.zeros(len(path))
    if len(path) > 2:
        span = path.s[2:] - path.s[:-2]
        ok = span > 1e-9
        hcurv0[1:-1] = np.where(ok, np.abs(hr_f[2:] - hr_f[:-2]) / np.where(ok, span, 1.0), 0.0)
    return curvature(path), hcurv0


def _refine(path: Path, resolution: float, use_path_speed: bool) -> _Grid:
    """Every segment of ``path`` refined into steps of at most ``resolution`` in sigma (a segment
    that does not move is skipped; ValueError when none moves)."""
    kappa0, hcurv0 = _point_curvatures(path)
    vfile0 = path.v if (use_path_speed and path.v is not None) else None
    ds0 = np.diff(path.s)
    dth0 = np.diff(path.theta)
    rows: list[tuple[float, ...]] = []  # one per grid point, in _Grid's order
    sigma = 0.0
    last_dir = (math.cos(path.theta[0]), math.sin(path.theta[0]))
    for i in range(len(path) - 1):
        ds, dth = float(ds0[i]), float(dth0[i])
        seg_sigma = math.hypot(ds, RHO * dth)
        if seg_sigma <= 1e-12:
            continue
        k = max(1, math.ceil(seg_sigma / resolution - 1e-9))
        direction = (
            ((path.x[i + 1] - path.x[i]) / ds, (path.y[i + 1] - path.y[i]) / ds) if ds > 0 else last_dir
        )
        last_dir = direction
        for j in range(k):
            f = j / k
            rows.append(
                (
                    path.x[i] + f * (path.x[i + 1] - path.x[i]),
                    path.y[i] + f * (path.y[i + 1] - path.y[i]),
                    path.theta[i] + f * dth,
                    path.s[i] + f * ds,
                    sigma + f * seg_sigma,
                    kappa0[i] + f * (kappa0[i + 1] - kappa0[i]),
                    hcurv0[i] + f * (hcurv0[i + 1] - hcurv0[i]),
                    math.inf if vfile0 is None else vfile0[i] + f * (vfile0[i + 1] - vfile0[i]),
                    ds / seg_sigma,
                    dth / seg_sigma,
                    *direction,
                )
            )
        sigma += seg_sigma
    if not rows:
        raise ValueError("the path does not move: every point is at the same pose")
    end = math.inf if vfile0 is None else vfile0[-1]
    rows.append(
        (
            path.x[-1],
            path.y[-1],
            path.theta[-1],
            path.s[-1],
            sigma,
            kappa0[-1],
            hcurv0[-1],
            end,
            *rows[-1][8:],
        )
    )
    return _Grid(*(list(column) for column in zip(*rows, strict=True)))


def _speed_cap(
    limits: MotionLimits, grid: _Grid, rs: FloatArray, rs_pt: FloatArray, rt_pt: FloatArray, K: FloatArray
) -> FloatArray:
    """The speed caps in u = dsigma/dt at each grid point (0 at both ends): v_max, w_max, the file's
    speed, the course rate, the wheels' and the floor's reach, then the grip's lateral and heading
    caps. ``rs_pt``/``rt_pt``: the larger |ds/dsigma|, |dtheta/dsigma| of the steps either side."""
    inf = math.inf
    HC = np.array(grid.hcurv)
    VF = np.array(grid.vfile)
    with np.errstate(divide="ignore", invalid="ignore"):
        cap: FloatArray = np.full(len(grid.x), inf)
        cap = np.minimum(cap, np.where(rs_pt > 0, limits.v_max / rs_pt, inf))
        cap = np.minimum(cap, np.where(rt_pt > 0, limits.w_max / rt_pt, inf))
        cap = np.minimum(cap, np.where(rs_pt > 0, VF / rs_pt, inf))
        if limits.course_rate is not None:
            cap = np.minimum(cap, np.where((K > 0) & (rs_pt > 0), limits.course_rate / (K * rs_pt), inf))
        if limits.wheels is not None or limits.floor is not None:
            thetas = np.array(grid.theta)
            cap = np.minimum(cap, _wheel_cap(limits, thetas, rs, np.array(grid.rt), grid.tx, grid.ty))
        # the grip's caps: lateral v^2 kappa and heading v^2 theta'' within the accelerations the
        # grip leaves at that speed (found from above: the fraction only grows as the speed falls)
        speed_cap = cap
        for _ in range(3 if limits.grip is not None else 1):
            left = limits.grip_at(np.where(np.isfinite(speed_cap), speed_cap * rs_pt, inf))
            lat = np.where(K > 0, np.sqrt(left * limits.lateral / K), inf)
            head = np.where(HC > 0, np.sqrt(0.5 * left * limits.alpha_max / HC), inf)
            speed_cap = np.minimum(cap, np.where(rs_pt > 0, np.minimum(lat, head) / rs_pt, inf))
        cap = speed_cap
    cap[0] = cap[-1] = 0.0
    return cap


def _accel_limit(
    limits: MotionLimits, rs_pt: FloatArray, rt_pt: FloatArray, K: FloatArray
) -> Callable[[int, float], float]:
    """``accel(j, u)``: the largest du/dt at grid point ``j`` at speed ``u``: what the lateral
    acceleration leaves of the friction ellipse, and alpha_max / 2, times the grip's fraction."""

    def accel(j: int, u: float) -> float:
        a = math.inf
        k = 1.0 if limits.grip is None else float(limits.grip_at(np.array([u * rs_pt[j]]))[0])
        if rs_pt[j] > 0:
            v = u * rs_pt[j]
            use = v * v * K[j] / (k * limits.lateral)
            a = min(a, k * limits.a_max * math.sqrt(max(0.0, 1.0 - use * use)) / rs_pt[j])
        if rt_pt[j] > 0:
            a = min(a, 0.5 * k * limits.alpha_max / rt_pt[j])
        return a if math.isfinite(a) else k * limits.a_max

    return accel


def _forward_backward(cap: FloatArray, dsig: FloatArray, accel: Callable[[int, float], float]) -> FloatArray:
    """The speeds u: accelerating as hard as allowed from rest, braking as late as allowed to rest
    at the end, within ``cap``."""
    n = len(cap)
    u = cap.copy()
    u[0] = 0.0
    for j in range(n - 1):
        reach = math.sqrt(u[j] * u[j] + 2.0 * accel(j, u[j]) * dsig[j])
        u[j + 1] = min(u[j + 1], reach)
    u[-1] = 0.0
    for j in range(n - 2, -1, -1):
        reach = math.sqrt(u[j + 1] * u[j + 1] + 2.0 * accel(j + 1, u[j + 1]) * dsig[j])
        u[j] = min(u[j], reach)
    return u


def _times(u: FloatArray, dsig: FloatArray, accel: Callable[[int, float], float]) -> FloatArray:
    """The time at each grid point, at constant acceleration over each step; from rest to rest in
    one step: accelerate, then brake."""
    t = np.zeros(len(u))
    for j in range(len(u) - 1):
        total = u[j] + u[j + 1]
        step = 2.0 * dsig[j] / total if total > 1e-12 else 2.0 * math.sqrt(dsig[j] / max(accel(j, 0.0), 1e-9))
        t[j + 1] = t[j] + step
    return t


def _wheel_cap(
    limits: MotionLimits, theta: FloatArray, rs: FloatArray, rt: FloatArray, tx: list[float], ty: list[float]
) -> FloatArray:
    """The largest u = d sigma/dt at each point for which no wheel exceeds ``wheel_use`` of its free
    speed and the twist ``floor_use`` of the floor's reach (the segment on either side of the
    point, whichever is the harder)."""
    c, s = np.cos(theta), np.sin(theta)
    tx_a, ty_a = np.array(tx), np.array(ty)
    # body-frame twist per unit u on the segment starting at each point
    bx, by = rs * (c * tx_a + s * ty_a), rs * (-s * tx_a + c * ty_a)
    cap = limits.reach(np.stack((bx, by, rt), axis=-1), limits.wheel_use, limits.floor_use)
    return np.minimum(cap, np.concatenate(([cap[0]], cap[:-1])))


def profile_within(path: Path, limits: MotionLimits, minimum: float, budget: float) -> SpeedProfile:
    """The time-optimal profile of ``path`` under ``limits``, their ``course_rate`` raised 1.1x a
    step (and at last dropped) until the profile takes at most ``budget`` x ``minimum`` s: the
    course-rate cap slows the turns where the odometry would drift, never past the time budget
    (a profile beyond it without the cap is returned as it is)."""
    profile = time_optimal_profile(path, limits)
    rate = limits.course_rate
    while rate is not None and profile.min_time > budget * minimum:
        rate = rate * 1.1 if rate < 20.0 * limits.w_max else None
        profile = time_optimal_profile(path, replace(limits, course_rate=rate))
    return profile


def min_traversal_time(path: Path, limits: MotionLimits) -> float:
    """Minimum time to drive ``path`` from rest to rest within ``limits`` (ignores the path's v)."""
    return time_optimal_profile(path, limits, use_path_speed=False).min_time
