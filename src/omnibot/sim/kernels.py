"""Compiled (numba) kernels of the simulator: the physics step, the world's contact geometry, the
sensors, one robot's whole step, and the laser scanner's ray casting.

The equations live here once; :mod:`omnibot.sim.physics`, :mod:`omnibot.sim.world`,
:mod:`omnibot.sim.sensors` and :mod:`omnibot.sim.simulator` hold the parameters and state as numpy
arrays and call these kernels with them. Every kernel loops over plain scalars and writes into
arrays its caller preallocated, so one call costs about a microsecond for one robot and scales
linearly with the number of robots.

* :func:`physics_step` advances n robots; :func:`physics_step_parallel` (``Physics.run``, the batch
  API) does the same for many steps with the robots shared out among numba's threads
  (:mod:`omnibot.sim.lanes` has its vectorised variant, not bit for bit);
* :func:`robot_step` is one :class:`~omnibot.sim.simulator.Simulator` step whole: surfaces,
  contacts and their forces, extra forces, the physics, the gyro and tracking wheels. Its state
  comes packed, as numba's dispatch costs about 0.1 us per array argument: the physics' arrays are
  views of one buffer (:func:`physics_offsets`), the world's geometry two (:func:`world_offsets`),
  the simulator's state two (the ``F_`` and ``I_`` headers, :func:`sim_offsets`), the gyro's and
  the tracking wheels' state one each (``G_`` and ``T_`` columns) and their normal draws one each;
  :func:`robot_before` and :func:`robot_after` are its parts around a physics of another kind;
  :func:`fleet_step` is :func:`robot_step` for every robot of a fleet in one call, their arrays
  views of the fleet's buffers (:mod:`omnibot.sim.fleet_arrays`);
* :func:`cone_distance` is a sonar's range, :func:`outline_contacts` the contact test,
  :func:`surface_probe` the floor lookup, ``scan_*`` the laser scanner.

Kernels compile lazily on their first call and are cached on disk (``cache=True``, next to this
file or in ``NUMBA_CACHE_DIR``), so a new process loads them instead of compiling. Callers always
pass the same argument types (C-contiguous float64 arrays, int64 id arrays, Python floats and
bools), so each kernel compiles exactly once. :func:`warm_up` compiles (or loads) every kernel with
those types at once; ``make setup`` runs it (``python -m omnibot.sim.jit``) to fill the cache at
install time. The simulator calls the kernels through :data:`omnibot.sim.jit.active`, which runs
their plain-Python twins while a first start compiles them in another process.

Parameter layouts (column indices below are compile-time constants):

* ``wp`` (n, m, W_COLUMNS): per wheel: the traction row ``W_TX..W_TA`` and roller row
  ``W_NX..W_NA`` of the contact matrix H (body vx, vy, w and wheel-speed coefficients), motor,
  driver and roller constants, the static load;
* ``rp`` (n, R_COLUMNS): per robot: mass / dt, yaw inertia / dt, battery resistance and relaxation;
* ``surf`` (S, S_COLUMNS): per floor surface: mu, 1 / slip velocity, rolling multiplier.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np
from numba import njit, prange
from numpy.typing import NDArray

from omnibot.floor import ROLL_SPEED_EPS, WHEEL_SPEED_EPS

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

# wheel parameter columns
W_TX, W_TY, W_TW, W_TA = 0, 1, 2, 3
W_NX, W_NY, W_NW, W_NA = 4, 5, 6, 7
W_J_DT = 8
W_INV_PWM_MAX = 9
W_ON_THRESHOLD = 10
W_DROP = 11
W_INV_RES = 12
W_KE_RES = 13
W_I_MAX = 14
W_KT = 15
W_EMF_DAMPING = 16
W_VISC = 17
W_STATIC = 18
W_LOAD = 19
W_GRIP_LOAD = 20
W_RR_TOP = 21
W_RR_VAR = 22
W_ROLLER_COUNT = 23
W_RADIUS = 24
W_SCRUB_LOAD = 25
W_COLUMNS = 26

# robot parameter columns
R_M_DT, R_I_DT, R_BATT_RES, R_BATT_RELAX = 0, 1, 2, 3
R_COLUMNS = 4

# surface table columns
S_MU, S_INV_VEPS, S_ROLL = 0, 1, 2
S_COLUMNS = 3

_INV_WHEEL_EPS = 1.0 / WHEEL_SPEED_EPS
_INV_ROLL_EPS = 1.0 / ROLL_SPEED_EPS

MERGE_COS = math.cos(math.radians(30.0))
"""Edge contacts of one owner whose normals are closer than 30 degrees are merged."""


# --------------------------------------------------------------------------- physics


@njit(cache=True)
def _contact_speeds(
    wp: FloatArray, i: int, j: int, vx: float, vy: float, w: float, omega: float
) -> tuple[float, float]:
    """Slip speed along the traction direction and roller rolling speed of wheel j of robot i."""
    p = wp[i, j]
    slip = p[W_TX] * vx + p[W_TY] * vy + p[W_TW] * w + p[W_TA] * omega
    roll = p[W_NX] * vx + p[W_NY] * vy + p[W_NW] * w + p[W_NA] * omega
    return slip, roll


@njit(cache=True)
def _secant(fmax: float, inv_eps: float, x: float) -> tuple[float, float]:
    """Regularised friction fmax tanh(x) and its secant slope d/d(speed) (fmax inv_eps at x = 0)."""
    th = math.tanh(x)
    ratio = th / x if x != 0.0 else 1.0
    return fmax * th, fmax * inv_eps * ratio


@njit(cache=True, inline="always")
def solve_body(
    s00: float, s11: float, s22: float, s01: float, s02: float, s12: float, r0: float, r1: float, r2: float
) -> tuple[float, float, float]:
    """The 3x3 body system s dq = r (s symmetric positive definite: the Schur complement of an SPD
    matrix) by Cholesky: dvx, dvy, dw."""
    l00 = math.sqrt(s00)
    l10, l20 = s01 / l00, s02 / l00
    l11 = math.sqrt(s11 - l10 * l10)
    l21 = (s12 - l20 * l10) / l11
    l22 = math.sqrt(s22 - l20 * l20 - l21 * l21)
    y0 = r0 / l00
    y1 = (r1 - l10 * y0) / l11
    y2 = (r2 - l20 * y0 - l21 * y1) / l22
    dw = y2 / l22
    dvy = (y1 - l21 * dw) / l11
    dvx = (y0 - l10 * dvy - l20 * dw) / l00
    return dvx, dvy, dw


@njit(cache=True, inline="always")
def _robot_physics(
    i: int,
    pose: FloatArray,
    q: FloatArray,
    wheel_angle: FloatArray,
    current: FloatArray,
    traction: FloatArray,
    battery: FloatArray,
    v_open: FloatArray,
    pwm: FloatArray,
    ids: IntArray,
    ext: FloatArray,
    has_ext: bool,
    wp: FloatArray,
    rp: FloatArray,
    surf: FloatArray,
    dt: float,
    scratch: FloatArray,
) -> None:
    """Advance robot i by dt in place (the body of :func:`physics_step`)."""
    m = wheel_angle.shape[1]
    vx, vy, w = q[i, 0], q[i, 1], q[i, 2]
    r = rp[i]
    v_bus = battery[i, 0]
    v_bus = v_bus + r[R_BATT_RELAX] * (v_open[i] - r[R_BATT_RES] * battery[i, 1] - v_bus)
    v_bus = max(v_bus, 0.0)
    s00, s11, s22 = r[R_M_DT], r[R_M_DT], r[R_I_DT]
    s01 = s02 = s12 = 0.0
    r0 = r1 = r2 = 0.0
    i_batt = 0.0
    for j in range(m):
        p = wp[i, j]
        omega = q[i, 3 + j]
        # driver and motor: current, and whether it follows the back-EMF (not limited)
        command = pwm[i, j]
        duty = min(max(command * p[W_INV_PWM_MAX], -1.0), 1.0)
        i_free = duty * (max(v_bus - p[W_DROP], 0.0) * p[W_INV_RES]) - p[W_KE_RES] * omega
        i_max = p[W_I_MAX]
        if abs(command) >= p[W_ON_THRESHOLD]:
            amps = min(max(i_free, -i_max), i_max)
            emf = p[W_EMF_DAMPING] if abs(i_free) < i_max else 0.0
        else:
            amps, emf = 0.0, 0.0
        # friction on the three contact rows: traction slip, roller rolling, axle
        sid = ids[i, j]
        inv_veps = surf[sid, S_INV_VEPS]
        roll_max = (p[W_RR_TOP] - p[W_RR_VAR] * math.cos(p[W_ROLLER_COUNT] * wheel_angle[i, j])) * (
            surf[sid, S_ROLL] * p[W_LOAD]
        )
        slip, roll = _contact_speeds(wp, i, j, vx, vy, w, omega)
        ft, kt = _secant(surf[sid, S_MU] * p[W_GRIP_LOAD], inv_veps, slip * inv_veps)
        fn, kn = _secant(roll_max, _INV_ROLL_EPS, roll * _INV_ROLL_EPS)
        fa, ka = _secant(p[W_STATIC], _INV_WHEEL_EPS, omega * _INV_WHEEL_EPS)
        # combined rolling and driving: viscous scrub on both rolling directions, weighted by
        # sin(2 beta) of the contact's direction (0 when the wheel or its rollers stand still)
        rim = p[W_RADIUS] * omega
        both = rim * rim + roll * roll
        if p[W_SCRUB_LOAD] > 0.0 and both > 1e-12:
            scrub = p[W_SCRUB_LOAD] * 2.0 * abs(rim) * abs(roll) / both
            fn += scrub * roll
            kn += scrub
            fa += scrub * p[W_RADIUS] * rim
            ka += scrub * p[W_RADIUS] * p[W_RADIUS]
        fa -= p[W_KT] * amps - p[W_VISC] * omega  # the motor drives the axle row
        ka += emf + p[W_VISC]
        traction[i, j] = -ft
        current[i, j] = amps
        i_batt += duty * amps
        # (M/dt + H^T K H) dq = -H^T f: accumulate, then eliminate this wheel's speed
        tx, ty, tw, ta = p[W_TX], p[W_TY], p[W_TW], p[W_TA]
        nx, ny, nw, na = p[W_NX], p[W_NY], p[W_NW], p[W_NA]
        r0 -= ft * tx + fn * nx
        r1 -= ft * ty + fn * ny
        r2 -= ft * tw + fn * nw
        rw = -(ft * ta + fn * na + fa)
        s00 += kt * tx * tx + kn * nx * nx
        s11 += kt * ty * ty + kn * ny * ny
        s22 += kt * tw * tw + kn * nw * nw
        s01 += kt * tx * ty + kn * nx * ny
        s02 += kt * tx * tw + kn * nx * nw
        s12 += kt * ty * tw + kn * ny * nw
        c0 = kt * ta * tx + kn * na * nx
        c1 = kt * ta * ty + kn * na * ny
        c2 = kt * ta * tw + kn * na * nw
        inv_d = 1.0 / (p[W_J_DT] + kt * ta * ta + kn * na * na + ka)
        e0, e1, e2 = c0 * inv_d, c1 * inv_d, c2 * inv_d
        s00 -= c0 * e0
        s11 -= c1 * e1
        s22 -= c2 * e2
        s01 -= c0 * e1
        s02 -= c0 * e2
        s12 -= c1 * e2
        r0 -= e0 * rw
        r1 -= e1 * rw
        r2 -= e2 * rw
        scratch[j, 0], scratch[j, 1], scratch[j, 2], scratch[j, 3], scratch[j, 4] = e0, e1, e2, inv_d, rw
    if has_ext:  # world force and torque, into the body frame
        c, s = math.cos(pose[i, 2]), math.sin(pose[i, 2])
        r0 += c * ext[i, 0] + s * ext[i, 1]
        r1 += c * ext[i, 1] - s * ext[i, 0]
        r2 += ext[i, 2]
    dvx, dvy, dw = solve_body(s00, s11, s22, s01, s02, s12, r0, r1, r2)
    for j in range(m):
        sc = scratch[j]
        q[i, 3 + j] += sc[4] * sc[3] - sc[0] * dvx - sc[1] * dvy - sc[2] * dw
    vx, vy, w = vx + dvx, vy + dvy, w + dw
    # body-frame rotation of the velocity by -w dt, pose at the mid-step heading, wheel angles
    c, s = math.cos(w * dt), math.sin(w * dt)
    vx, vy = vx * c + vy * s, vy * c - vx * s
    q[i, 0], q[i, 1], q[i, 2] = vx, vy, w
    heading = pose[i, 2] + 0.5 * dt * w
    c, s = math.cos(heading), math.sin(heading)
    pose[i, 0] += (c * vx - s * vy) * dt
    pose[i, 1] += (s * vx + c * vy) * dt
    pose[i, 2] += dt * w
    for j in range(m):
        wheel_angle[i, j] += dt * q[i, 3 + j]
    battery[i, 0] = v_bus
    battery[i, 1] = i_batt


@njit(cache=True)
def _ids_valid(ids: IntArray, n_surf: int) -> bool:
    for i in range(ids.shape[0]):
        for j in range(ids.shape[1]):
            if ids[i, j] < 0 or ids[i, j] >= n_surf:
                return False
    return True


@njit(cache=True)
def physics_step(
    pose: FloatArray,
    q: FloatArray,
    wheel_angle: FloatArray,
    current: FloatArray,
    traction: FloatArray,
    battery: FloatArray,
    v_open: FloatArray,
    pwm: FloatArray,
    ids: IntArray,
    ext: FloatArray,
    has_ext: bool,
    wp: FloatArray,
    rp: FloatArray,
    surf: FloatArray,
    dt: float,
) -> int:
    """Advance every robot by dt in place (see :mod:`omnibot.sim.physics` for the equations).

    ``battery`` (n, 2) holds the bus voltage and battery current of the last step. The linearised
    backward-Euler system has an arrow structure (a dense 3x3 body block, a diagonal wheel block):
    the wheels are eliminated one by one (Schur complement), the 3x3 body system is solved by
    Cholesky, then the wheel speeds are substituted back; exact, in O(m) per robot.
    Returns 0, or 1 (state untouched) if a surface id is out of range.
    """
    if not _ids_valid(ids, surf.shape[0]):
        return 1
    scratch = np.empty((wheel_angle.shape[1], 5))  # per wheel: coupling c / d (3), 1 / d, right-hand side
    for i in range(wheel_angle.shape[0]):
        _robot_physics(
            i, pose, q, wheel_angle, current, traction, battery, v_open, pwm, ids, ext, has_ext, wp, rp, surf, dt,
            scratch,
        )  # fmt: skip
    return 0


@njit(cache=True, parallel=True)
def physics_step_parallel(
    buf: FloatArray, ids: IntArray, n: int, m: int, n_surf: int, has_ext: bool, dt: float, steps: int
) -> int:
    """:func:`physics_step` ``steps`` times on a physics state packed in ``buf``
    (:func:`physics_views`), the robots shared out among numba's threads.

    Each robot is advanced ``steps`` steps in a row by one thread (its state stays in that core's
    cache); robots are independent, so the result is the same as ``steps`` calls of
    :func:`physics_step`, bit for bit, whatever the number of threads.
    """
    pose, q, wheel_angle, current, traction, battery, v_open, pwm, ext, wp, rp, surf = physics_views(
        buf, n, m, n_surf
    )
    if not _ids_valid(ids, n_surf):
        return 1
    chunk = 16  # robots per task: few enough tasks to keep the threads' overhead small
    for c in prange((n + chunk - 1) // chunk):
        scratch = np.empty((m, 5))
        for i in range(c * chunk, min(n, (c + 1) * chunk)):
            for _ in range(steps):
                _robot_physics(
                    i, pose, q, wheel_angle, current, traction, battery, v_open, pwm, ids, ext, has_ext, wp, rp,
                    surf, dt, scratch,
                )  # fmt: skip
    return 0


@njit(cache=True)
def physics_offsets(
    n: int, m: int, n_surf: int
) -> tuple[int, int, int, int, int, int, int, int, int, int, int, int, int]:
    """Where each array of a physics state packed in one float64 buffer starts (and its size, last):
    pose (n, 3), q (n, 3 + m), wheel_angle, current, traction (n, m), battery (n, 2), v_open (n,),
    pwm (n, m), ext (n, 3), wp (n, m, W_COLUMNS), rp (n, R_COLUMNS), surf (n_surf, S_COLUMNS)."""
    o0 = 0
    o1 = o0 + 3 * n
    o2 = o1 + (3 + m) * n
    o3 = o2 + n * m
    o4 = o3 + n * m
    o5 = o4 + n * m
    o6 = o5 + 2 * n
    o7 = o6 + n
    o8 = o7 + n * m
    o9 = o8 + 3 * n
    o10 = o9 + n * m * W_COLUMNS
    o11 = o10 + n * R_COLUMNS
    return o0, o1, o2, o3, o4, o5, o6, o7, o8, o9, o10, o11, o11 + n_surf * S_COLUMNS


@njit(cache=True)
def physics_views(
    buf: FloatArray, n: int, m: int, n_surf: int
) -> tuple[
    FloatArray, FloatArray, FloatArray, FloatArray, FloatArray, FloatArray,
    FloatArray, FloatArray, FloatArray, FloatArray, FloatArray, FloatArray,
]:  # fmt: skip
    """The arrays of a packed physics state (:func:`physics_offsets`) as views of ``buf``."""
    o = physics_offsets(n, m, n_surf)
    return (
        buf[o[0] : o[1]].reshape((n, 3)),
        buf[o[1] : o[2]].reshape((n, 3 + m)),
        buf[o[2] : o[3]].reshape((n, m)),
        buf[o[3] : o[4]].reshape((n, m)),
        buf[o[4] : o[5]].reshape((n, m)),
        buf[o[5] : o[6]].reshape((n, 2)),
        buf[o[6] : o[7]],
        buf[o[7] : o[8]].reshape((n, m)),
        buf[o[8] : o[9]].reshape((n, 3)),
        buf[o[9] : o[10]].reshape((n, m, W_COLUMNS)),
        buf[o[10] : o[11]].reshape((n, R_COLUMNS)),
        buf[o[11] : o[12]].reshape((n_surf, S_COLUMNS)),
    )


@njit(cache=True)
def contact_speeds(q: FloatArray, wp: FloatArray, out: FloatArray) -> None:
    """Fill out (n, m, 2) with each wheel's slip speed and roller rolling speed (m/s)."""
    n, m = out.shape[0], out.shape[1]
    for i in range(n):
        for j in range(m):
            out[i, j, 0], out[i, j, 1] = _contact_speeds(wp, i, j, q[i, 0], q[i, 1], q[i, 2], q[i, 3 + j])


# --------------------------------------------------------------------------- world geometry


@njit(cache=True)
def _inside(px: float, py: float, verts: FloatArray, lo: int, hi: int) -> bool:
    """Crossing-number test of one point against the closed polygon verts[lo:hi] (bounding box first)."""
    xmin, ymin, xmax, ymax = np.inf, np.inf, -np.inf, -np.inf
    for k in range(lo, hi):
        xmin, xmax = min(xmin, verts[k, 0]), max(xmax, verts[k, 0])
        ymin, ymax = min(ymin, verts[k, 1]), max(ymax, verts[k, 1])
    if not (xmin <= px <= xmax and ymin <= py <= ymax):
        return False
    inside = False
    for k in range(lo, hi):
        k1 = k + 1 if k + 1 < hi else lo
        x0, y0, x1, y1 = verts[k, 0], verts[k, 1], verts[k1, 0], verts[k1, 1]
        if (y0 > py) != (y1 > py):
            dy = y1 - y0
            slope = (x1 - x0) / dy if dy != 0.0 else 0.0
            if px < x0 + (py - y0) * slope:
                inside = not inside
    return inside


@njit(cache=True)
def _segment_distance(px: float, py: float, x0: float, y0: float, x1: float, y1: float) -> float:
    ex, ey = x1 - x0, y1 - y0
    ee = ex * ex + ey * ey
    t = ((px - x0) * ex + (py - y0) * ey) / ee if ee > 0.0 else 0.0
    t = min(max(t, 0.0), 1.0)
    return math.hypot(x0 + t * ex - px, y0 + t * ey - py)


@njit(cache=True)
def surface_probe(
    points: FloatArray, verts: FloatArray, offsets: IntArray, surface: IntArray, out: IntArray
) -> float:
    """Surface id under each point (later polygons win, 0 outside all) into out; returns the clearance.

    Polygon k is verts[offsets[k]:offsets[k+1]] with surface id surface[k]. The clearance is the
    smallest distance from any point to any polygon edge: the points may each move less than that
    without changing their surface.
    """
    clearance = np.inf
    for a in range(points.shape[0]):
        px, py = points[a, 0], points[a, 1]
        sid = 0
        for k in range(surface.shape[0]):
            lo, hi = offsets[k], offsets[k + 1]
            if _inside(px, py, verts, lo, hi):
                sid = surface[k]
            for e in range(lo, hi):
                e1 = e + 1 if e + 1 < hi else lo
                d = _segment_distance(px, py, verts[e, 0], verts[e, 1], verts[e1, 0], verts[e1, 1])
                clearance = min(clearance, d)
        out[a] = sid
    return clearance


@njit(cache=True)
def _add_normals(v: FloatArray, lo: int, hi: int, closed: bool, axes: FloatArray, count: int) -> int:
    """Append the unit edge normals of polygon v[lo:hi] (one for a 2-vertex segment) to axes."""
    n_edges = hi - lo if closed else hi - lo - 1
    for k in range(lo, lo + n_edges):
        k1 = k + 1 if k + 1 < hi else lo
        ex, ey = v[k1, 0] - v[k, 0], v[k1, 1] - v[k, 1]
        length = math.hypot(ey, -ex)
        if length > 1e-12:
            axes[count, 0], axes[count, 1] = ey / length, -ex / length
            count += 1
    return count


@njit(cache=True)
def _sat(
    robot: FloatArray, other: FloatArray, lo: int, hi: int, closed: bool, axes: FloatArray, depth: FloatArray
) -> tuple[bool, float, float, float, float, float]:
    """Separating-axis test of the convex robot outline against the convex other[lo:hi].

    ``closed`` False means other is one segment (two vertices, one axis). Returns (hit, point x,
    point y, normal x, normal y, depth): the normal pushes the robot out along the shallowest axis
    (toward its side of each axis; on a tie the other shape's own face, listed last).
    """
    nr = robot.shape[0]
    count = _add_normals(robot, 0, nr, True, axes, 0)
    count = _add_normals(other, lo, hi, closed, axes, count)
    crx = cry = cox = coy = 0.0
    for k in range(nr):
        crx += robot[k, 0]
        cry += robot[k, 1]
    for k in range(lo, hi):
        cox += other[k, 0]
        coy += other[k, 1]
    crx, cry, cox, coy = crx / nr, cry / nr, cox / (hi - lo), coy / (hi - lo)
    best = np.inf
    for a in range(count):
        ax, ay = axes[a, 0], axes[a, 1]
        rmin, rmax, omin, omax = np.inf, -np.inf, np.inf, -np.inf
        for k in range(nr):
            pr = robot[k, 0] * ax + robot[k, 1] * ay
            rmin, rmax = min(rmin, pr), max(rmax, pr)
        for k in range(lo, hi):
            po = other[k, 0] * ax + other[k, 1] * ay
            omin, omax = min(omin, po), max(omax, po)
        plus, minus = omax - rmin, rmax - omin  # move the robot along +axis / -axis by this to clear
        if plus <= 0.0 or minus <= 0.0:
            return False, 0.0, 0.0, 0.0, 0.0, 0.0
        side = (crx - cox) * ax + (cry - coy) * ay
        if side > 1e-12:
            dep, sign = plus, 1.0
        elif side < -1e-12:
            dep, sign = minus, -1.0
        else:
            dep, sign = min(plus, minus), (1.0 if plus <= minus else -1.0)
        depth[a, 0], depth[a, 1] = dep, sign
        best = min(best, dep)
    k = 0
    for a in range(count):
        if depth[a, 0] <= best + 1e-9 + 1e-6 * best:
            k = a
    nx, ny = axes[k, 0] * depth[k, 1], axes[k, 1] * depth[k, 1]
    tx, ty = -ny, nx
    # contact point: middle of the overlap, along the face, of the two deepest features
    tol = 1e-6 + 1e-3 * best
    pr_min, po_max = np.inf, -np.inf
    for j in range(nr):
        pr_min = min(pr_min, robot[j, 0] * nx + robot[j, 1] * ny)
    for j in range(lo, hi):
        po_max = max(po_max, other[j, 0] * nx + other[j, 1] * ny)
    r_lo, r_hi, r_sum, r_n = np.inf, -np.inf, 0.0, 0
    for j in range(nr):
        if robot[j, 0] * nx + robot[j, 1] * ny <= pr_min + tol:
            f = robot[j, 0] * tx + robot[j, 1] * ty
            r_lo, r_hi, r_sum, r_n = min(r_lo, f), max(r_hi, f), r_sum + f, r_n + 1
    o_lo, o_hi, o_sum, o_n = np.inf, -np.inf, 0.0, 0
    for j in range(lo, hi):
        if other[j, 0] * nx + other[j, 1] * ny >= po_max - tol:
            f = other[j, 0] * tx + other[j, 1] * ty
            o_lo, o_hi, o_sum, o_n = min(o_lo, f), max(o_hi, f), o_sum + f, o_n + 1
    lo_f, hi_f = max(r_lo, o_lo), min(r_hi, o_hi)
    along = 0.5 * (lo_f + hi_f) if lo_f <= hi_f else 0.5 * (r_sum / r_n + o_sum / o_n)
    across = 0.5 * (pr_min + po_max)
    return True, along * tx + across * nx, along * ty + across * ny, nx, ny, best


@njit(cache=True)
def outline_contacts(
    body: FloatArray,
    x: float,
    y: float,
    theta: float,
    solid_v: FloatArray,
    solid_off: IntArray,
    solid_c: FloatArray,
    solid_r: FloatArray,
    solid_owner: IntArray,
    thin_v: FloatArray,
    thin_owner: IntArray,
    out: FloatArray,
) -> tuple[int, float]:
    """Contacts of a convex outline (body frame, placed at pose x, y, theta) with the world.

    Solid convex obstacles (solid_v[solid_off[k]:solid_off[k+1]], bounding circle solid_c, solid_r)
    are tested whole; thin edges (walls, non-convex obstacles; edge k is thin_v[2k:2k+2]) one by one,
    and contacts of one owner whose normals are within 30 degrees are merged (the deepest kept).
    Writes rows (point x, point y, normal x, normal y, depth, owner id) to out and returns
    (count, clearance): the outline's origin may move less than ``clearance`` (any rotation)
    without touching anything (0 when touching, or inside a solid).
    """
    nv = body.shape[0]
    c, s = math.cos(theta), math.sin(theta)
    v = np.empty((nv, 2))
    reach0 = 0.0
    for k in range(nv):
        bx, by = body[k, 0], body[k, 1]
        v[k, 0], v[k, 1] = bx * c - by * s + x, bx * s + by * c + y
        reach0 = max(reach0, math.hypot(bx, by))
    cx = cy = 0.0
    for k in range(nv):
        cx += v[k, 0]
        cy += v[k, 1]
    cx, cy = cx / nv, cy / nv
    reach = 0.0
    for k in range(nv):
        reach = max(reach, math.hypot(v[k, 0] - cx, v[k, 1] - cy))
    longest = 2
    for k in range(solid_owner.shape[0]):
        longest = max(longest, solid_off[k + 1] - solid_off[k])
    axes = np.empty((nv + longest, 2))
    depth = np.empty((nv + longest, 2))
    count = first_edge = 0
    nearest = np.inf
    inside_solid = False
    n_solid = solid_owner.shape[0]
    for k in range(n_solid + thin_owner.shape[0]):
        if k < n_solid:  # a solid: its edges, whether the origin is inside, its bounding circle
            verts, lo, hi, closed, owner = solid_v, solid_off[k], solid_off[k + 1], True, solid_owner[k]
            for e in range(lo, hi):
                e1 = e + 1 if e + 1 < hi else lo
                d = _segment_distance(x, y, verts[e, 0], verts[e, 1], verts[e1, 0], verts[e1, 1])
                nearest = min(nearest, d)
            inside_solid = inside_solid or _inside(x, y, verts, lo, hi)
            near = math.hypot(solid_c[k, 0] - cx, solid_c[k, 1] - cy) < reach + solid_r[k]
        else:  # a thin edge: near if its closest point to the centre is within reach
            e = k - n_solid
            verts, lo, hi, closed, owner = thin_v, 2 * e, 2 * e + 2, False, thin_owner[e]
            x0, y0, x1, y1 = verts[lo, 0], verts[lo, 1], verts[lo + 1, 0], verts[lo + 1, 1]
            nearest = min(nearest, _segment_distance(x, y, x0, y0, x1, y1))
            ex, ey = x1 - x0, y1 - y0
            t = min(max(((cx - x0) * ex + (cy - y0) * ey) / (ex * ex + ey * ey), 0.0), 1.0)
            gx, gy = x0 + t * ex - cx, y0 + t * ey - cy
            near = gx * gx + gy * gy < reach * reach
        if not near:
            continue
        hit, px, py, nx, ny, dep = _sat(v, verts, lo, hi, closed, axes, depth)
        if not hit:
            continue
        a = count
        if not closed:  # edge contacts stay sorted by depth, deepest first (stable for equal depths)
            while a > first_edge and out[a - 1, 4] < dep:
                for col in range(6):
                    out[a, col] = out[a - 1, col]
                a -= 1
        out[a, 0], out[a, 1], out[a, 2], out[a, 3], out[a, 4], out[a, 5] = px, py, nx, ny, dep, owner
        count += 1
        if closed:
            first_edge = count
    kept = first_edge
    for a in range(first_edge, count):
        keep = True
        for b in range(first_edge, kept):
            if out[b, 5] == out[a, 5] and out[b, 2] * out[a, 2] + out[b, 3] * out[a, 3] >= MERGE_COS:
                keep = False
                break
        if keep:
            for col in range(6):
                out[kept, col] = out[a, col]
            kept += 1
    clearance = nearest - reach0 - 1e-9
    if kept > 0 or inside_solid or not clearance > 0.0:
        clearance = 0.0
    return kept, clearance


@njit(cache=True)
def cone_distance(
    segments: FloatArray, x: float, y: float, heading: float, cone: float, max_range: float
) -> float:
    """Distance from (x, y) to the nearest point of any edge ``(K, 4)`` within ``heading +- cone/2``
    (inf if none within max_range; cone in (0, pi)): each edge clipped to the cone, then its point
    nearest the apex taken (:func:`omnibot.sim.geometry.cone_range`)."""
    half = cone / 2
    r0, r1 = math.cos(heading - half), math.sin(heading - half)
    l0, l1 = math.cos(heading + half), math.sin(heading + half)
    best = np.inf
    for k in range(segments.shape[0]):
        ax, ay = segments[k, 0] - x, segments[k, 1] - y
        ex, ey = segments[k, 2] - segments[k, 0], segments[k, 3] - segments[k, 1]
        lo, hi = 0.0, 1.0
        # inside the cone: cross(r, p) >= 0 and cross(p, left) >= 0, each linear in t along the edge
        for side in range(2):
            if side == 0:
                f0, f1 = r0 * ay - r1 * ax, r0 * ey - r1 * ex
            else:
                f0, f1 = ax * l1 - ay * l0, ex * l1 - ey * l0
            if f1 > 1e-15:
                lo = max(lo, -f0 / f1)
            elif f1 < -1e-15:
                hi = min(hi, -f0 / f1)
            elif f0 < 0:
                hi = -1.0
        if not lo <= hi:
            continue
        ee = ex * ex + ey * ey
        t = -(ax * ex + ay * ey) / ee if ee > 0 else 0.0
        t = min(max(t, lo), max(lo, hi))
        best = min(best, math.hypot(ax + t * ex, ay + t * ey))
    return best if best <= max_range else np.inf


# --------------------------------------------------------------------------- sensors

# gyro state columns (one float64 array per gyro)
G_BIAS, G_SCALE, G_SIGMA, G_WALK, G_DUE, G_PERIOD, G_RANGE, G_RESOLUTION = 0, 1, 2, 3, 4, 5, 6, 7
G_ACC_TIME, G_ACC_ANGLE, G_RATE, G_ANGLE, G_SAMPLES, G_NEXT = 8, 9, 10, 11, 12, 13
G_COLUMNS = 14
"""G_NEXT: index of the next unused normal draw in the gyro's block."""

# tracking wheels state: T_SLIP, T_NEXT, then per wheel (ux, uy, px, py, distance)
T_SLIP, T_NEXT, T_HEADER, T_WHEEL = 0, 1, 2, 5


@njit(cache=True)
def gyro_measure(g: FloatArray, normals: FloatArray, true_rate: float) -> float:
    """One sample of a (period-averaged) true rate into g (see :class:`omnibot.sim.sensors.Gyro`);
    normal draws from ``normals`` at g[G_NEXT] on."""
    k = int(g[G_NEXT])
    if g[G_WALK] > 0:
        g[G_BIAS] += g[G_WALK] * normals[k]
        k += 1
    noise = 0.0
    if g[G_SIGMA] > 0:
        noise = g[G_SIGMA] * normals[k]
        k += 1
    g[G_NEXT] = k
    limit, resolution = g[G_RANGE], g[G_RESOLUTION]
    value = (1.0 + g[G_SCALE]) * true_rate + g[G_BIAS] + noise
    value = min(max(value, -limit), limit)
    if resolution > 0:
        value = round(value / resolution) * resolution
        value = min(max(value, -limit), limit)
    g[G_RATE] = value
    g[G_ANGLE] += value * g[G_PERIOD]
    g[G_SAMPLES] += 1.0
    return float(value)


@njit(cache=True)
def gyro_update(g: FloatArray, normals: FloatArray, dt: float, true_rate: float) -> bool:
    """Advance the gyro g by dt at true_rate; True if it took at least one sample."""
    g[G_ACC_TIME] += dt
    g[G_ACC_ANGLE] += true_rate * dt
    if g[G_ACC_TIME] < g[G_DUE]:
        return False
    while g[G_ACC_TIME] >= g[G_DUE]:
        mean = g[G_ACC_ANGLE] / g[G_ACC_TIME]
        g[G_ACC_TIME] -= g[G_PERIOD]
        g[G_ACC_ANGLE] = mean * g[G_ACC_TIME]
        gyro_measure(g, normals, mean)
    return True


@njit(cache=True)
def tracking_update(t: FloatArray, normals: FloatArray, vx: float, vy: float, w: float, dt: float) -> None:
    """Roll the tracking wheels t for dt at the body twist (see :class:`omnibot.sim.sensors.TrackingWheels`)."""
    slip_std = t[T_SLIP]
    k = int(t[T_NEXT])
    for a in range(T_HEADER, t.shape[0], T_WHEEL):
        ux, uy, px, py = t[a], t[a + 1], t[a + 2], t[a + 3]
        step = ((vx - w * py) * ux + (vy + w * px) * uy) * dt
        if slip_std > 0:
            step = step * (1.0 + slip_std * normals[k])
            k += 1
        t[a + 4] = t[a + 4] + step
    t[T_NEXT] = k


# --------------------------------------------------------------------------- one robot's whole step

# the simulator's float state (sf): header, then outline (V, 2), contact rows (C, 6), contact
# speeds (C,), wheel positions (m, 2)
F_MASS, F_INERTIA, F_OMEGA, F_DAMPING, F_WALL_FRICTION = 0, 1, 2, 3, 4
F_CLEAR_X, F_CLEAR_Y, F_CLEAR = 5, 6, 7
F_SURF_X, F_SURF_Y, F_SURF_TH, F_SURF_CLEAR, F_REACH = 8, 9, 10, 11, 12
F_AT_X, F_AT_Y, F_AT_TH = 13, 14, 15
F_HEADER = 16
# its int state (si): header, then last touch (us) per world owner, new-collision flags (C,),
# world surface id -> physics surface id, surface ids of the last probe (m,)
I_V, I_C, I_M, I_OWNERS, I_SURFACES, I_COUNT, I_WALLS, I_PATCHY, I_RELEASE = 0, 1, 2, 3, 4, 5, 6, 7, 8
I_HEADER = 9
NEVER = -(2**62)
"""A last-touch time meaning 'never touched'."""
# the world's packed geometry: wf floats solid_v (V, 2), solid_c (K, 2), solid_r (K,), thin_v (2E, 2),
# patch_v (P, 2); wi ints: the sizes V, K, E, P, Q, then solid_off (K + 1), solid_owner (K),
# thin_owner (E), patch_off (Q + 1), patch_sid (Q)
WORLD_HEADER = 5

# robot_step status bits
STEP_BAD_SURFACE, STEP_COLLISION, STEP_REFILL, STEP_FORCE = 1, 2, 4, 8


@njit(cache=True)
def world_offsets(wi: IntArray) -> tuple[int, int, int, int, int, int, int, int, int, int, int]:
    """Where each array of a packed world starts: (solid_v, solid_c, solid_r, thin_v, patch_v, end
    of wf; solid_off, solid_owner, thin_owner, patch_off, patch_sid in wi)."""
    nv, nk, ne, npv, nq = wi[0], wi[1], wi[2], wi[3], wi[4]
    f0 = 0
    f1 = f0 + 2 * nv
    f2 = f1 + 2 * nk
    f3 = f2 + nk
    f4 = f3 + 4 * ne
    f5 = f4 + 2 * npv
    i0 = WORLD_HEADER
    i1 = i0 + nk + 1
    i2 = i1 + nk
    i3 = i2 + ne
    i4 = i3 + nq + 1
    return f0, f1, f2, f3, f4, f5, i0, i1, i2, i3, i4


@njit(cache=True)
def sim_offsets(si: IntArray) -> tuple[int, int, int, int, int, int, int, int, int, int]:
    """Where each array of the simulator's state starts: (outline, contact rows, contact speeds,
    wheel positions, end of sf; last touch, new flags, surface map, probed ids, end of si)."""
    nv, nc, m = si[I_V], si[I_C], si[I_M]
    f0 = F_HEADER
    f1 = f0 + 2 * nv
    f2 = f1 + 6 * nc
    f3 = f2 + nc
    f4 = f3 + 2 * m
    i0 = I_HEADER
    i1 = i0 + si[I_OWNERS]
    i2 = i1 + nc
    i3 = i2 + si[I_SURFACES]
    i4 = i3 + m
    return f0, f1, f2, f3, f4, i0, i1, i2, i3, i4


@njit(cache=True)
def _world_contacts(
    wf: FloatArray, wi: IntArray, body: FloatArray, x: float, y: float, th: float, out: FloatArray
) -> tuple[int, float]:
    f0, f1, f2, f3, f4, _, i0, i1, i2, _, _ = world_offsets(wi)
    nv, nk, ne = wi[0], wi[1], wi[2]
    return outline_contacts(
        body, x, y, th,
        wf[f0:f1].reshape((nv, 2)), wi[i0:i1], wf[f1:f2].reshape((nk, 2)), wf[f2:f3], wi[i1:i2],
        wf[f3:f4].reshape((2 * ne, 2)), wi[i2 : i2 + ne], out,
    )  # fmt: skip


@njit(cache=True)
def _before_physics(
    x: float,
    y: float,
    th: float,
    vx: float,
    vy: float,
    w: float,
    ids: IntArray,
    wf: FloatArray,
    wi: IntArray,
    sf: FloatArray,
    si: IntArray,
    extra: FloatArray,
    n_extra: int,
    ext: FloatArray,
    now_us: int,
) -> int:
    """The floor under the wheels into ids (when a wheel may have changed patch) and the world's
    push-back plus the extra forces into ext[0] (STEP_FORCE set when it is not zero)."""
    of0, of1, of2, of3, _, oi0, oi1, oi2, oi3, _ = sim_offsets(si)
    m = si[I_M]
    status = 0
    if si[I_PATCHY]:
        moved = math.hypot(x - sf[F_SURF_X], y - sf[F_SURF_Y]) + abs(th - sf[F_SURF_TH]) * sf[F_REACH]
        if moved >= sf[F_SURF_CLEAR] - 1e-9:
            c, s = math.cos(th), math.sin(th)
            points = np.empty((m, 2))
            for j in range(m):
                wx, wy = sf[of3 + 2 * j], sf[of3 + 2 * j + 1]
                points[j, 0] = x + c * wx - s * wy
                points[j, 1] = y + s * wx + c * wy
            _, _, _, _, fp, _, _, _, _, ip, isid = world_offsets(wi)
            nq = wi[4]
            local = si[oi3 : oi3 + m]
            if nq:
                clearance = surface_probe(
                    points, wf[fp : fp + 2 * wi[3]].reshape((wi[3], 2)), wi[ip : ip + nq + 1],
                    wi[isid : isid + nq], local,
                )  # fmt: skip
            else:
                clearance = np.inf
                local[:] = 0
            for j in range(m):
                ids[0, j] = si[oi2 + local[j]]
            sf[F_SURF_X], sf[F_SURF_Y], sf[F_SURF_TH], sf[F_SURF_CLEAR] = x, y, th, clearance
    fx = fy = tz = 0.0
    if si[I_WALLS]:
        dx, dy = x - sf[F_CLEAR_X], y - sf[F_CLEAR_Y]
        clear = sf[F_CLEAR]
        if clear <= 0.0 or dx * dx + dy * dy >= clear * clear:
            nc = si[I_C]
            out = sf[of1:of2].reshape((nc, 6))
            count, clearance = _world_contacts(wf, wi, sf[of0:of1].reshape((si[I_V], 2)), x, y, th, out)
            sf[F_CLEAR_X], sf[F_CLEAR_Y], sf[F_CLEAR] = x, y, clearance
            sf[F_AT_X], sf[F_AT_Y], sf[F_AT_TH] = x, y, th
            si[I_COUNT] = count
            if count:
                c, s = math.cos(th), math.sin(th)
                vwx, vwy = c * vx - s * vy, s * vx + c * vy
                m_body, inertia, omega = sf[F_MASS], sf[F_INERTIA], sf[F_OMEGA]
                damping, wall_friction = sf[F_DAMPING], sf[F_WALL_FRICTION]
                for a in range(count):
                    px, py, nx, ny, depth = out[a, 0], out[a, 1], out[a, 2], out[a, 3], out[a, 4]
                    rx, ry = px - x, py - y
                    pvx, pvy = vwx - w * ry, vwy + w * rx
                    vn, vt = pvx * nx + pvy * ny, -pvx * ny + pvy * nx
                    rn = rx * ny - ry * nx
                    m_eff = 1.0 / (1.0 / m_body + rn * rn / inertia)
                    fn = max(0.0, m_eff * omega * omega * depth - 2 * damping * m_eff * omega * vn)
                    ft = -wall_friction * fn * math.tanh(vt / 0.05)
                    fxa, fya = fn * nx - ft * ny, fn * ny + ft * nx
                    fx, fy, tz = fx + fxa, fy + fya, tz + (rx * fya - ry * fxa)
                    sf[of2 + a] = -vn
                    owner = oi0 + int(out[a, 5])
                    last = si[owner]
                    si[owner] = now_us
                    fresh = last == NEVER or now_us - last > si[I_RELEASE]
                    si[oi1 + a] = 1 if fresh else 0
                    if fresh:
                        status |= STEP_COLLISION
    for k in range(n_extra):
        fx, fy, tz = fx + extra[k, 0], fy + extra[k, 1], tz + extra[k, 2]
    if fx or fy or tz:
        ext[0, 0], ext[0, 1], ext[0, 2] = fx, fy, tz
        status |= STEP_FORCE
    return status


@njit(cache=True)
def _after_physics(
    vx0: float,
    vy0: float,
    w0: float,
    vx1: float,
    vy1: float,
    w1: float,
    dt: float,
    gyro: FloatArray,
    gyro_normals: FloatArray,
    tracking: FloatArray,
    tracking_normals: FloatArray,
) -> int:
    """The gyro and tracking wheels over a step whose twist went from 0 to 1 (STEP_REFILL when
    either has fewer normal draws left than two steps may take)."""
    status = 0
    if tracking.shape[0] > T_HEADER:
        tracking_update(tracking, tracking_normals, 0.5 * (vx0 + vx1), 0.5 * (vy0 + vy1), 0.5 * (w0 + w1), dt)
        if tracking_normals.shape[0] - int(tracking[T_NEXT]) < 2 * (tracking.shape[0] - T_HEADER):
            status |= STEP_REFILL
    if gyro.shape[0]:
        gyro_update(gyro, gyro_normals, dt, 0.5 * (w0 + w1))
        if gyro_normals.shape[0] - int(gyro[G_NEXT]) < 4 * (int(dt / gyro[G_PERIOD]) + 2):
            status |= STEP_REFILL
    return status


@njit(cache=True)
def robot_step(
    pbuf: FloatArray,
    ids: IntArray,
    m: int,
    n_surf: int,
    wf: FloatArray,
    wi: IntArray,
    sf: FloatArray,
    si: IntArray,
    extra: FloatArray,
    n_extra: int,
    gyro: FloatArray,
    gyro_normals: FloatArray,
    tracking: FloatArray,
    tracking_normals: FloatArray,
    now_us: int,
    dt: float,
) -> int:
    """One whole step of one robot alone (a :class:`omnibot.sim.simulator.Simulator`): the floor
    under its wheels, the push-back of the walls and obstacles it touches plus ``extra`` forces
    (rows added in order), the physics (state packed in ``pbuf``: :func:`physics_views`), and the
    gyro and tracking wheels. Returns the STEP_ status bits (STEP_BAD_SURFACE: nothing moved)."""
    pose, q, wheel_angle, current, traction, battery, v_open, pwm, ext, wp, rp, surf = physics_views(
        pbuf, 1, m, n_surf
    )
    x, y, th = pose[0, 0], pose[0, 1], pose[0, 2]
    vx0, vy0, w0 = q[0, 0], q[0, 1], q[0, 2]
    status = _before_physics(x, y, th, vx0, vy0, w0, ids, wf, wi, sf, si, extra, n_extra, ext, now_us)
    if not _ids_valid(ids, n_surf):
        return status | STEP_BAD_SURFACE
    scratch = np.empty((m, 5))
    has_ext = status & STEP_FORCE != 0
    _robot_physics(
        0, pose, q, wheel_angle, current, traction, battery, v_open, pwm, ids, ext, has_ext, wp, rp, surf, dt,
        scratch,
    )  # fmt: skip
    return status | _after_physics(
        vx0, vy0, w0, q[0, 0], q[0, 1], q[0, 2], dt, gyro, gyro_normals, tracking, tracking_normals
    )


# a fleet's layout (fleet_step): one row per robot, where its arrays lie in the fleet's buffers
(
    L_PBUF, L_PBUF_END, L_M, L_N_SURF, L_SF, L_SF_END, L_GYRO, L_GYRO_END, L_TRACKING, L_TRACKING_END,
    L_IDS, L_SI, L_SI_END, L_GYRO_NORMALS, L_GYRO_NORMALS_END, L_TRACKING_NORMALS, L_TRACKING_NORMALS_END,
    L_EXTRA, L_N_EXTRA,
) = range(19)  # fmt: skip
L_COLUMNS = 19


@njit(cache=True)
def fleet_step(
    fbuf: FloatArray,
    ibuf: IntArray,
    layout: IntArray,
    wf: FloatArray,
    wi: IntArray,
    normals: FloatArray,
    extra: FloatArray,
    status: IntArray,
    now_us: int,
    dt: float,
) -> int:
    """One :func:`robot_step` of every robot of a fleet in one call (numba's dispatch, about 1 us of
    unboxing eleven arrays, paid once a step rather than once a robot). Robot k's arrays are views of
    the fleet's buffers where row k of ``layout`` says (``L_`` columns: the physics buffer, the
    simulator's float state, the gyro's and tracking wheels' state in ``fbuf``; the surface ids and
    the simulator's int state in ``ibuf``; the normal draws in ``normals``; its extra force rows in
    ``extra``); all share the world ``wf``, ``wi``. Robot k's status bits go into ``status[k]``;
    returns them all or-ed (a robot whose ids are bad stops nothing of the others)."""
    every = 0
    for k in range(layout.shape[0]):
        row = layout[k]
        m = row[L_M]
        s = robot_step(
            fbuf[row[L_PBUF] : row[L_PBUF_END]], ibuf[row[L_IDS] : row[L_IDS] + m].reshape((1, m)), m,
            row[L_N_SURF], wf, wi, fbuf[row[L_SF] : row[L_SF_END]], ibuf[row[L_SI] : row[L_SI_END]],
            extra[row[L_EXTRA] : row[L_EXTRA] + row[L_N_EXTRA]], row[L_N_EXTRA],
            fbuf[row[L_GYRO] : row[L_GYRO_END]], normals[row[L_GYRO_NORMALS] : row[L_GYRO_NORMALS_END]],
            fbuf[row[L_TRACKING] : row[L_TRACKING_END]],
            normals[row[L_TRACKING_NORMALS] : row[L_TRACKING_NORMALS_END]], now_us, dt,
        )  # fmt: skip
        status[k] = s
        every |= s
    return every


@njit(cache=True)
def robot_before(
    state: FloatArray,
    ids: IntArray,
    wf: FloatArray,
    wi: IntArray,
    sf: FloatArray,
    si: IntArray,
    extra: FloatArray,
    n_extra: int,
    ext: FloatArray,
    now_us: int,
) -> int:
    """The part of :func:`robot_step` before the physics, for a physics of another kind: ``state``
    holds the pose and twist (x, y, theta, vx, vy, w) now; the force goes into ext[0]."""
    return _before_physics(
        state[0], state[1], state[2], state[3], state[4], state[5], ids, wf, wi, sf, si, extra, n_extra, ext,
        now_us,
    )  # fmt: skip


@njit(cache=True)
def robot_after(
    state: FloatArray,
    dt: float,
    gyro: FloatArray,
    gyro_normals: FloatArray,
    tracking: FloatArray,
    tracking_normals: FloatArray,
) -> int:
    """The part of :func:`robot_step` after the physics: ``state`` holds the twist before and after."""
    return _after_physics(
        state[0], state[1], state[2], state[3], state[4], state[5], dt, gyro, gyro_normals, tracking,
        tracking_normals,
    )  # fmt: skip


# --------------------------------------------------------------------------- laser scanner

SCAN_BINS = 256
"""Directions of a :func:`scan_index`: the circle is cut into this many equal sectors."""


@njit(cache=True)
def _turn(a: float) -> float:
    """a wrapped to [0, 2 pi)."""
    return a - 2.0 * math.pi * math.floor(a / (2.0 * math.pi))


@njit(cache=True)
def _hit(ox: float, oy: float, dx: float, dy: float, x0: float, y0: float, x1: float, y1: float) -> float:
    """Distance along the ray (ox, oy) + t (dx, dy) to the edge (x0, y0)-(x1, y1), inf if it misses."""
    ex, ey = x1 - x0, y1 - y0
    denom = dx * ey - dy * ex
    if abs(denom) < 1e-12:
        return np.inf
    ax, ay = x0 - ox, y0 - oy
    t = (ax * ey - ay * ex) / denom
    u = (ax * dy - ay * dx) / denom
    return t if t >= 0.0 and 0.0 <= u <= 1.0 else np.inf


@njit(cache=True)
def scan_index(
    segments: FloatArray, ax: float, ay: float, radius: float, max_range: float
) -> tuple[IntArray, IntArray, FloatArray]:
    """Which edges a ray from anywhere within ``radius`` of (ax, ay) may meet, by direction.

    Returns (starts, entries, near): the edges a ray pointing into sector b (of SCAN_BINS equal
    sectors from angle 0) may meet are entries[starts[b]:starts[b+1]], nearest first; near[e] is no
    more than the distance from any such origin to edge e. An edge seen from (ax, ay) under the angles
    [a, a + s] is seen from an origin within ``radius`` under angles within asin(radius / d) of them
    (d: the edge's distance from (ax, ay)), so it goes into the sectors of that widened interval;
    an edge closer than ``radius`` into every sector; one farther than max_range + radius into none.
    """
    n_seg = segments.shape[0]
    width = 2.0 * math.pi / SCAN_BINS
    near = np.full(n_seg, np.inf)
    first = np.zeros(n_seg, dtype=np.int64)
    count = np.zeros(n_seg, dtype=np.int64)
    for e in range(n_seg):
        x0, y0, x1, y1 = segments[e, 0], segments[e, 1], segments[e, 2], segments[e, 3]
        d = _segment_distance(ax, ay, x0, y0, x1, y1)
        if d - radius > max_range:
            continue
        near[e] = d - radius
        if d <= radius:
            count[e] = SCAN_BINS
            continue
        a0 = math.atan2(y0 - ay, x0 - ax)
        span = _wrap(math.atan2(y1 - ay, x1 - ax) - a0)
        if span < 0.0:
            a0, span = a0 + span, -span
        widen = math.asin(min(1.0, radius / d)) + 1e-9
        a0, span = _turn(a0 - widen), span + 2.0 * widen
        lo = min(int(a0 / width), SCAN_BINS - 1)
        first[e] = lo
        count[e] = min(int((a0 + span) / width) - lo + 1, SCAN_BINS)
    order = np.argsort(near)
    starts = np.zeros(SCAN_BINS + 1, dtype=np.int64)
    for e in range(n_seg):
        for k in range(count[e]):
            starts[(first[e] + k) % SCAN_BINS + 1] += 1
    for b in range(SCAN_BINS):
        starts[b + 1] += starts[b]
    fill = starts[:-1].copy()
    entries = np.empty(starts[SCAN_BINS], dtype=np.int64)
    for q in range(n_seg):
        e = order[q]
        for k in range(count[e]):
            b = (first[e] + k) % SCAN_BINS
            entries[fill[b]] = e
            fill[b] += 1
    return starts, entries, near


@njit(cache=True)
def _wrap(a: float) -> float:
    """a wrapped to [-pi, pi)."""
    return a - 2.0 * math.pi * math.floor((a + math.pi) / (2.0 * math.pi))


@njit(cache=True)
def scan_rays(
    ray_t: FloatArray,
    ray_a: FloatArray,
    hist_t0: float,
    hist_dt: float,
    hist_p: FloatArray,
    own: int,
    mount_x: float,
    mount_y: float,
    segments: FloatArray,
    starts: IntArray,
    entries: IntArray,
    near: FloatArray,
    body_v: FloatArray,
    body_off: IntArray,
    max_range: float,
    out: FloatArray,
) -> None:
    """True range of each ray of a spinning scanner into out (inf: nothing within max_range).

    Ray i is measured at time ray_t[i] in direction ray_a[i] of the robot's base frame, from the
    scanner at (mount_x, mount_y) in that frame. Poses are recorded every hist_dt seconds from
    hist_t0: row j of hist_p holds (x, y, theta) of every body b in columns 3b..3b+2; the scanner's
    robot is body ``own``. Each body's pose at a ray's time is interpolated linearly between rows
    (held outside them). The rays meet the world's edges (``x0, y0, x1, y1`` rows of segments) and
    the other bodies' outlines (body b: the closed polygon body_v[body_off[b]:body_off[b+1]] in its
    own frame) where those bodies were at the ray's time.

    A ray tests only the edges (starts, entries, near) of :func:`scan_index` lists for its direction,
    nearest first, and stops at the first whose ``near`` lies beyond its hit (the index must hold
    every origin); a body only if its bounding circle meets the ray. The result is the same as
    testing everything.
    """
    n = ray_t.shape[0]
    n_hist = hist_p.shape[0]
    n_body = body_off.shape[0] - 1
    body_r = np.zeros(n_body)
    for b in range(n_body):
        for v in range(body_off[b], body_off[b + 1]):
            body_r[b] = max(body_r[b], math.hypot(body_v[v, 0], body_v[v, 1]))
    width = 2.0 * math.pi / SCAN_BINS
    c0 = 3 * own
    for i in range(n):
        pos = (ray_t[i] - hist_t0) / hist_dt
        k = min(max(math.floor(pos), 0), max(n_hist - 2, 0))
        f = min(max(pos - k, 0.0), 1.0) if n_hist > 1 else 0.0
        k1 = k + 1 if n_hist > 1 else k
        x = hist_p[k, c0] + f * (hist_p[k1, c0] - hist_p[k, c0])
        y = hist_p[k, c0 + 1] + f * (hist_p[k1, c0 + 1] - hist_p[k, c0 + 1])
        th = hist_p[k, c0 + 2] + f * (hist_p[k1, c0 + 2] - hist_p[k, c0 + 2])
        c, s = math.cos(th), math.sin(th)
        ox = x + c * mount_x - s * mount_y
        oy = y + s * mount_x + c * mount_y
        ang = th + ray_a[i]
        dx, dy = math.cos(ang), math.sin(ang)
        sector = min(int(_turn(ang) / width), SCAN_BINS - 1)
        best = np.inf
        for q in range(starts[sector], starts[sector + 1]):
            e = entries[q]
            if near[e] > best:
                break
            t = _hit(ox, oy, dx, dy, segments[e, 0], segments[e, 1], segments[e, 2], segments[e, 3])
            best = min(best, t)
        for b in range(n_body):
            if b == own:
                continue
            cb = 3 * b
            bx = hist_p[k, cb] + f * (hist_p[k1, cb] - hist_p[k, cb])
            by = hist_p[k, cb + 1] + f * (hist_p[k1, cb + 1] - hist_p[k, cb + 1])
            rx, ry = bx - ox, by - oy
            along = rx * dx + ry * dy
            r = body_r[b]
            if along + r < 0.0 or along - r > best or abs(rx * dy - ry * dx) > r:
                continue  # its bounding circle is behind, beyond the best hit or beside the ray
            bt = hist_p[k, cb + 2] + f * (hist_p[k1, cb + 2] - hist_p[k, cb + 2])
            cbt, sbt = math.cos(bt), math.sin(bt)
            px, py = -cbt * rx - sbt * ry, sbt * rx - cbt * ry  # the origin in the body's frame
            qx, qy = cbt * dx + sbt * dy, -sbt * dx + cbt * dy  # the direction in the body's frame
            v0, v1 = body_off[b], body_off[b + 1]
            for v in range(v0, v1):
                w = v + 1 if v + 1 < v1 else v0
                t = _hit(px, py, qx, qy, body_v[v, 0], body_v[v, 1], body_v[w, 0], body_v[w, 1])
                best = min(best, t)
        out[i] = best if best <= max_range else np.inf


@njit(cache=True)
def scan_measure(
    true: FloatArray,
    draws: FloatArray,
    noise_std: float,
    noise_fraction: float,
    resolution: float,
    dropout: float,
    range_min: float,
    range_max: float,
    out: FloatArray,
) -> None:
    """What the scanner reports for the true ranges (inf: no return) into out, from 3 uniform draws
    per ray (draws[i], draws[n + i], draws[2n + i]: a Box-Muller normal from the first two, the
    dropout from the third): the range plus N(0, noise_std + noise_fraction * range), quantised to
    resolution (when > 0); inf for a dropout or a value outside [range_min, range_max]."""
    n = true.shape[0]
    for i in range(n):
        r = true[i]
        if not r < np.inf or draws[2 * n + i] < dropout:
            out[i] = np.inf
            continue
        z = math.sqrt(-2.0 * math.log1p(-draws[i])) * math.cos(2.0 * math.pi * draws[n + i])
        v = r + (noise_std + noise_fraction * r) * z
        if resolution > 0.0:
            v = round(v / resolution) * resolution
        out[i] = v if range_min <= v <= range_max else np.inf


SIMULATOR_KERNELS = (
    outline_contacts,
    robot_step,
    fleet_step,
    cone_distance,
    scan_index,
    scan_rays,
    scan_measure,
)
"""The kernels a simulator of one robot calls (the helpers they call compile with them; Python
calls :func:`physics_offsets` and :func:`sim_offsets` as plain Python, their ``py_func``)."""
KERNELS = (
    *SIMULATOR_KERNELS, physics_step, contact_speeds, surface_probe, robot_before, robot_after, gyro_update,
    gyro_measure, tracking_update,
)  # fmt: skip
"""Every serial kernel (:func:`physics_step_parallel`, for batches, compiles on its first call)."""


def warm_up_calls() -> list[tuple[Any, Callable[[], object]]]:
    """(kernel, call) for every kernel in :data:`KERNELS` order: the call compiles (or loads) it with
    the argument types the simulator passes (empty or trivial arrays: nothing is computed)."""

    def f(*shape: int) -> FloatArray:
        return np.zeros(shape)

    def i(*shape: int) -> IntArray:
        return np.zeros(shape, dtype=np.int64)

    triangle = np.array([[0.1, 0.0], [-0.1, 0.1], [-0.1, -0.1]])
    si = i(I_HEADER)
    si_full = i(int(sim_offsets.py_func(si)[-1]))
    no_world = i(WORLD_HEADER + 2)
    index = (i(SCAN_BINS + 1), i(0), f(0))
    gyro = f(G_COLUMNS)
    gyro[G_DUE] = gyro[G_PERIOD] = 1.0
    # robot_step with no surface returns STEP_BAD_SURFACE before it moves anything; fleet_step has no robot
    one_robot = (
        f(int(physics_offsets.py_func(1, 1, 0)[-1])), i(1, 1), 1, 0, f(0), no_world, f(F_HEADER), si_full,
        f(1, 3), 0, f(0), f(0), f(2), f(0), 0, 0.001,
    )  # fmt: skip
    calls: dict[Any, Callable[[], object]] = {
        outline_contacts: lambda: outline_contacts(
            triangle, 0.0, 0.0, 0.0, f(0, 2), i(1), f(0, 2), f(0), i(0), f(0, 2), i(0), f(0, 6)
        ),
        robot_step: lambda: robot_step(*one_robot),
        fleet_step: lambda: fleet_step(
            f(0), i(0), i(0, L_COLUMNS), f(0), no_world, f(0), f(0, 3), i(0), 0, 0.001
        ),
        cone_distance: lambda: cone_distance(f(0, 4), 0.0, 0.0, 0.0, 0.5, 1.0),
        scan_index: lambda: scan_index(f(0, 4), 0.0, 0.0, 1.0, 1.0),
        scan_rays: lambda: scan_rays(
            f(0), f(0), 0.0, 0.001, f(1, 3), 0, 0.0, 0.0, f(0, 4), *index, f(0, 2), i(2), 1.0, f(0)
        ),
        scan_measure: lambda: scan_measure(f(0), f(0), 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, f(0)),
        physics_step: lambda: physics_step(
            f(1, 3),
            f(1, 4),
            f(1, 1),
            f(1, 1),
            f(1, 1),
            f(1, 2),
            f(1),
            f(1, 1),
            i(1, 1),
            f(1, 3),
            False,
            f(1, 1, W_COLUMNS),
            f(1, R_COLUMNS),
            f(0, S_COLUMNS),
            0.001,
        ),
        contact_speeds: lambda: contact_speeds(f(0, 3), f(0, 0, W_COLUMNS), f(0, 0, 2)),
        surface_probe: lambda: surface_probe(f(0, 2), f(0, 2), i(1), i(0), i(0)),
        robot_before: lambda: robot_before(
            f(6), i(1, 1), f(0), no_world, f(F_HEADER), si_full, f(1, 3), 0, f(1, 3), 0
        ),
        robot_after: lambda: robot_after(f(6), 0.001, f(0), f(0), f(2), f(0)),
        gyro_update: lambda: gyro_update(gyro, f(0), 0.0, 0.0),
        gyro_measure: lambda: gyro_measure(f(G_COLUMNS), f(0), 0.0),
        tracking_update: lambda: tracking_update(f(T_HEADER), f(0), 0.0, 0.0, 0.0, 0.001),
    }
    return [(kernel, calls[kernel]) for kernel in KERNELS]


def warm_up(every: bool = True) -> None:
    """Compile every kernel of :data:`KERNELS` and :func:`physics_step_parallel` now (only the
    :data:`SIMULATOR_KERNELS` with ``every`` False), or load it from the disk cache, with the
    argument types the simulator passes. About a second per kernel on the first run of a fresh
    install (:func:`robot_step`, which compiles the physics, contacts and sensors with it, takes
    most), milliseconds once the cache is filled."""
    for kernel, call in warm_up_calls():
        if every or kernel in SIMULATOR_KERNELS:
            call()
    if every:  # the batch's kernel too (no surface: it returns before it moves anything)
        buf = np.zeros(physics_offsets.py_func(1, 1, 0)[-1])
        physics_step_parallel(buf, np.zeros((1, 1), dtype=np.int64), 1, 1, 0, False, 0.001, 0)


__all__ = [
    "KERNELS",
    "SIMULATOR_KERNELS",
    "cone_distance",
    "contact_speeds",
    "fleet_step",
    "gyro_measure",
    "gyro_update",
    "outline_contacts",
    "physics_offsets",
    "physics_step",
    "physics_step_parallel",
    "physics_views",
    "robot_after",
    "robot_before",
    "robot_step",
    "scan_index",
    "scan_measure",
    "scan_rays",
    "sim_offsets",
    "solve_body",
    "surface_probe",
    "tracking_update",
    "warm_up",
    "warm_up_calls",
    "world_offsets",
]
