"""The physics kernels: wheels, motors, drivers, rollers and floor friction, one backward-Euler step.

:func:`physics_step` advances n robots (the equations: :mod:`omnibot.sim.physics`);
:func:`physics_step_parallel` (``Physics.run``, the batch API) does the same for many steps with
the robots shared out among numba's threads (:mod:`omnibot.sim.kernels.lanes` has its vectorised variant,
not bit for bit); :func:`robot_physics` is one robot's step, which the whole step of
:mod:`omnibot.sim.kernels.step` calls too.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from omnibot.floor import ROLL_SPEED_EPS, WHEEL_SPEED_EPS
from omnibot.sim.kernels.layout import (
    R_BATT_RELAX,
    R_BATT_RES,
    R_I_DT,
    R_M_DT,
    S_INV_VEPS,
    S_MU,
    S_ROLL,
    W_DROP,
    W_EMF_DAMPING,
    W_GRIP_LOAD,
    W_I_MAX,
    W_INV_PWM_MAX,
    W_INV_RES,
    W_J_DT,
    W_KE_RES,
    W_KT,
    W_LOAD,
    W_NA,
    W_NW,
    W_NX,
    W_NY,
    W_ON_THRESHOLD,
    W_RADIUS,
    W_ROLLER_COUNT,
    W_RR_TOP,
    W_RR_VAR,
    W_SCRUB_LOAD,
    W_STATIC,
    W_TA,
    W_TW,
    W_TX,
    W_TY,
    W_VISC,
    FloatArray,
    IntArray,
    physics_views,
)

_INV_WHEEL_EPS = 1.0 / WHEEL_SPEED_EPS
_INV_ROLL_EPS = 1.0 / ROLL_SPEED_EPS


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
def _drive(p: FloatArray, command: float, v_bus: float, omega: float) -> tuple[float, float, float]:
    """Driver and motor of a wheel (parameters p) at wheel speed omega: (duty, current, the back-EMF's
    damping when the current follows it, not limited, else 0)."""
    duty = min(max(command * p[W_INV_PWM_MAX], -1.0), 1.0)
    i_free = duty * (max(v_bus - p[W_DROP], 0.0) * p[W_INV_RES]) - p[W_KE_RES] * omega
    i_max = p[W_I_MAX]
    if abs(command) >= p[W_ON_THRESHOLD]:
        amps = min(max(i_free, -i_max), i_max)
        emf = p[W_EMF_DAMPING] if abs(i_free) < i_max else 0.0
    else:
        amps, emf = 0.0, 0.0
    return duty, amps, emf


@njit(cache=True, inline="always")
def _friction(
    p: FloatArray, surf: FloatArray, sid: int, angle: float, slip: float, roll: float, omega: float
) -> Forces:
    """Friction forces and secant slopes on a wheel's three contact rows on surface sid: traction
    slip (ft, kt), roller rolling (fn, kn), axle (fa, ka), with the scrub of combined rolling and
    driving."""
    inv_veps = surf[sid, S_INV_VEPS]
    roll_max = (p[W_RR_TOP] - p[W_RR_VAR] * math.cos(p[W_ROLLER_COUNT] * angle)) * (
        surf[sid, S_ROLL] * p[W_LOAD]
    )
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
    return ft, kt, fn, kn, fa, ka


Forces = tuple[float, float, float, float, float, float]
"""A wheel's forces and secant slopes on its three contact rows: ft, kt (traction), fn, kn (roller
rolling), fa, ka (axle)."""
Body = tuple[float, float, float, float, float, float, float, float, float]
"""The body system's upper triangle and right-hand side: s00, s11, s22, s01, s02, s12, r0, r1, r2."""


@njit(cache=True, inline="always")
def _add_wheel(body: Body, p: FloatArray, forces: Forces, sc: FloatArray) -> Body:
    """(M/dt + H^T K H) dq = -H^T f: a wheel's rows added to the body system, its speed eliminated
    (its elimination factors e0, e1, e2, 1/d and right-hand side into sc, for :func:`_advance`)."""
    s00, s11, s22, s01, s02, s12, r0, r1, r2 = body
    ft, kt, fn, kn, fa, ka = forces
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
    sc[0], sc[1], sc[2], sc[3], sc[4] = e0, e1, e2, inv_d, rw
    return s00, s11, s22, s01, s02, s12, r0, r1, r2


@njit(cache=True, inline="always")
def _advance(
    i: int,
    pose: FloatArray,
    q: FloatArray,
    wheel_angle: FloatArray,
    scratch: FloatArray,
    dv: tuple[float, float, float],
    dt: float,
) -> None:
    """Robot i's wheel speeds, twist, pose and wheel angles after the body's speed change dv (dvx,
    dvy, dw) of a step of dt."""
    dvx, dvy, dw = dv
    m = wheel_angle.shape[1]
    for j in range(m):
        sc = scratch[j]
        q[i, 3 + j] += sc[4] * sc[3] - sc[0] * dvx - sc[1] * dvy - sc[2] * dw
    vx, vy, w = q[i, 0] + dvx, q[i, 1] + dvy, q[i, 2] + dw
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


@njit(cache=True, inline="always")
def robot_physics(
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
    vx, vy, w = q[i, 0], q[i, 1], q[i, 2]
    r = rp[i]
    v_bus = battery[i, 0]
    v_bus = v_bus + r[R_BATT_RELAX] * (v_open[i] - r[R_BATT_RES] * battery[i, 1] - v_bus)
    v_bus = max(v_bus, 0.0)
    body = (r[R_M_DT], r[R_M_DT], r[R_I_DT], 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    i_batt = 0.0
    for j in range(wheel_angle.shape[1]):
        p = wp[i, j]
        omega = q[i, 3 + j]
        duty, amps, emf = _drive(p, pwm[i, j], v_bus, omega)
        slip, roll = _contact_speeds(wp, i, j, vx, vy, w, omega)
        ft, kt, fn, kn, fa, ka = _friction(p, surf, ids[i, j], wheel_angle[i, j], slip, roll, omega)
        fa -= p[W_KT] * amps - p[W_VISC] * omega  # the motor drives the axle row
        ka += emf + p[W_VISC]
        traction[i, j] = -ft
        current[i, j] = amps
        i_batt += duty * amps
        body = _add_wheel(body, p, (ft, kt, fn, kn, fa, ka), scratch[j])
    s00, s11, s22, s01, s02, s12, r0, r1, r2 = body
    if has_ext:  # world force and torque, into the body frame
        c, s = math.cos(pose[i, 2]), math.sin(pose[i, 2])
        r0 += c * ext[i, 0] + s * ext[i, 1]
        r1 += c * ext[i, 1] - s * ext[i, 0]
        r2 += ext[i, 2]
    _advance(i, pose, q, wheel_angle, scratch, solve_body(s00, s11, s22, s01, s02, s12, r0, r1, r2), dt)
    battery[i, 0] = v_bus
    battery[i, 1] = i_batt


@njit(cache=True)
def ids_valid(ids: IntArray, n_surf: int) -> bool:
    """Whether every surface id is one of the n_surf surfaces."""
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
    if not ids_valid(ids, surf.shape[0]):
        return 1
    scratch = np.empty((wheel_angle.shape[1], 5))  # per wheel: coupling c / d (3), 1 / d, right-hand side
    for i in range(wheel_angle.shape[0]):
        robot_physics(
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
    if not ids_valid(ids, n_surf):
        return 1
    chunk = 16  # robots per task: few enough tasks to keep the threads' overhead small
    for c in prange((n + chunk - 1) // chunk):
        scratch = np.empty((m, 5))
        for i in range(c * chunk, min(n, (c + 1) * chunk)):
            for _ in range(steps):
                robot_physics(
                    i, pose, q, wheel_angle, current, traction, battery, v_open, pwm, ids, ext, has_ext, wp, rp,
                    surf, dt, scratch,
                )  # fmt: skip
    return 0


@njit(cache=True)
def contact_speeds(q: FloatArray, wp: FloatArray, out: FloatArray) -> None:
    """Fill out (n, m, 2) with each wheel's slip speed and roller rolling speed (m/s)."""
    n, m = out.shape[0], out.shape[1]
    for i in range(n):
        for j in range(m):
            out[i, j, 0], out[i, j, 1] = _contact_speeds(wp, i, j, q[i, 0], q[i, 1], q[i, 2], q[i, 3 + j])
