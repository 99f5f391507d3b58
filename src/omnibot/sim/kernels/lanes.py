"""The batch physics laid out for throughput: robots side by side in vector lanes.

:func:`physics_run` advances the robots of a packed physics state (:func:`~omnibot.sim.kernels.physics_views`)
by many steps, as :func:`~omnibot.sim.kernels.physics_step_parallel` does, with the same equations
(:mod:`omnibot.sim.physics`) in the same order of IEEE double operations, but laid out so the
compiler vectorises it: each thread copies a block of :data:`BLOCK` robots into a structure of
arrays (one row per quantity, one column per robot) and steps them together, every loop over the
block's robots innermost. Numba calls the C library's ``tanh``, ``cos`` and ``sin`` one value at a
time (no vector library here: numba finds no SVML), which would keep the loops scalar and took
over half of an exact robot-step; it has its own, in plain arithmetic (:mod:`omnibot.sim.kernels.libm`:
:func:`~omnibot.sim.kernels.libm.tanh`, :func:`~omnibot.sim.kernels.libm.sincos`, :func:`~omnibot.sim.kernels.libm.cos`).

They are not the C library's, so the results are not :meth:`Physics.step`'s bit for bit: each
function is within about one unit in the last place of the exact value (``tests/sim/kernels/test_libm.py``
measures it), and a run keeps within a stated tolerance of the exact step's
(``docs/simulator.md``, "Batches"). Everything else is exact IEEE arithmetic compiled without
``fastmath``: the result does not depend on the number of threads, the block's vector width or the
CPU, and the kernel's Python twin (:func:`omnibot.sim.twins.python_twins`) gives the same numbers.
The simulator never calls this module (its steps stay :func:`~omnibot.sim.kernels.robot_step`'s,
bit for bit); :meth:`Physics.run` does when asked ``exact=False``, compiling it on its first call in
a process (a few seconds; cached on disk after).

Range: :mod:`~omnibot.sim.kernels.libm`'s sine and cosine reduce their argument by pi/2 in three exact parts, good for
``|x| <= REDUCE_LIMIT``; the kernel gives larger angles (a heading or a wheel angle past a million
radians) to the C library, one value at a time.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from omnibot.floor import ROLL_SPEED_EPS, WHEEL_SPEED_EPS
from omnibot.sim.kernels import layout
from omnibot.sim.kernels.layout import FloatArray, IntArray, physics_offsets, physics_views
from omnibot.sim.kernels.libm import REDUCE_LIMIT, cos, sincos, tanh
from omnibot.sim.kernels.wheels import Forces, solve_body

BLOCK = 32
"""Robots stepped together by one thread (a multiple of any vector width)."""


# rows of a block's structure of arrays, one column per robot: per robot ...
(X, Y, TH, VX, VY, W, V_BUS, I_BATT, V_OPEN, EXT_X, EXT_Y, EXT_T, M_DT, I_DT, B_RES, B_RELAX,
 S00, S11, S22, S01, S02, S12, R0, R1, R2, I_SUM, ARG, SIN, COS, ARG2, SIN2, COS2) = range(32)  # fmt: skip
ROBOT_ROWS = 32
# ... and per wheel (rows j WHEEL_ROWS + column of another array)
(TX, TY, TW, TA, NX, NY, NW, NA, J_DT, DUTY, ON, DROP, INV_RES, KE_RES, I_MAX, EMF, KT, VISC, STATIC,
 F_TRACTION, INV_VEPS, ROLL_LOAD, RR_TOP, RR_VAR, COUNT, RADIUS, SCRUB, OMEGA, ANGLE, CURRENT, TRACTION,
 E0, E1, E2, INV_D, RW, WARG, WCOS) = range(38)  # fmt: skip
WHEEL_ROWS = 38

_INV_WHEEL_EPS = 1.0 / WHEEL_SPEED_EPS
_INV_ROLL_EPS = 1.0 / ROLL_SPEED_EPS


@njit(cache=True, inline="always", error_model="numpy")
def _far(a: float) -> int:
    """1 if :func:`sincos` cannot reduce ``a`` (past :data:`REDUCE_LIMIT`, or not finite), else 0."""
    return 0 if abs(a) <= REDUCE_LIMIT else 1


@njit(cache=True, inline="always", error_model="numpy")
def _fix_range(b: FloatArray, arg: int, sin: int, cos: int) -> None:
    """The C library's sin and cos of the arguments past :data:`REDUCE_LIMIT` (or not finite)."""
    for i in range(BLOCK):
        a = b[arg, i]
        if not abs(a) <= REDUCE_LIMIT:
            b[cos, i] = math.cos(a)
            if sin >= 0:
                b[sin, i] = math.sin(a)


@njit(cache=True, error_model="numpy")
def _load(
    rb: FloatArray, wb: FloatArray, first: int, n: int, m: int, views: tuple[FloatArray, ...], ids: IntArray
) -> None:
    """Copy robots first.. of the packed state into a block (lanes past n repeat robot n - 1)."""
    pose, q, wheel_angle, current, traction, battery, v_open, pwm, ext, wp, rp, surf = views
    for lane in range(BLOCK):
        i = min(first + lane, n - 1)
        rb[X, lane], rb[Y, lane], rb[TH, lane] = pose[i, 0], pose[i, 1], pose[i, 2]
        rb[VX, lane], rb[VY, lane], rb[W, lane] = q[i, 0], q[i, 1], q[i, 2]
        rb[V_BUS, lane], rb[I_BATT, lane], rb[V_OPEN, lane] = battery[i, 0], battery[i, 1], v_open[i]
        rb[EXT_X, lane], rb[EXT_Y, lane], rb[EXT_T, lane] = ext[i, 0], ext[i, 1], ext[i, 2]
        r = rp[i]
        rb[M_DT, lane], rb[I_DT, lane] = r[layout.R_M_DT], r[layout.R_I_DT]
        rb[B_RES, lane], rb[B_RELAX, lane] = r[layout.R_BATT_RES], r[layout.R_BATT_RELAX]
        for j in range(m):
            o = j * WHEEL_ROWS
            p = wp[i, j]
            for c in range(8):  # the contact rows TX..NA are wp's first 8 columns
                wb[o + c, lane] = p[c]
            command = pwm[i, j]
            wb[o + J_DT, lane] = p[layout.W_J_DT]
            wb[o + DUTY, lane] = min(max(command * p[layout.W_INV_PWM_MAX], -1.0), 1.0)
            wb[o + ON, lane] = 1.0 if abs(command) >= p[layout.W_ON_THRESHOLD] else 0.0
            wb[o + DROP, lane], wb[o + INV_RES, lane] = p[layout.W_DROP], p[layout.W_INV_RES]
            wb[o + KE_RES, lane], wb[o + I_MAX, lane] = p[layout.W_KE_RES], p[layout.W_I_MAX]
            wb[o + EMF, lane], wb[o + KT, lane] = p[layout.W_EMF_DAMPING], p[layout.W_KT]
            wb[o + VISC, lane], wb[o + STATIC, lane] = p[layout.W_VISC], p[layout.W_STATIC]
            sid = ids[i, j]
            wb[o + F_TRACTION, lane] = surf[sid, layout.S_MU] * p[layout.W_GRIP_LOAD]
            wb[o + INV_VEPS, lane] = surf[sid, layout.S_INV_VEPS]
            wb[o + ROLL_LOAD, lane] = surf[sid, layout.S_ROLL] * p[layout.W_LOAD]
            wb[o + RR_TOP, lane], wb[o + RR_VAR, lane] = p[layout.W_RR_TOP], p[layout.W_RR_VAR]
            wb[o + COUNT, lane], wb[o + RADIUS, lane] = p[layout.W_ROLLER_COUNT], p[layout.W_RADIUS]
            wb[o + SCRUB, lane] = p[layout.W_SCRUB_LOAD]
            wb[o + OMEGA, lane], wb[o + ANGLE, lane] = q[i, 3 + j], wheel_angle[i, j]
            wb[o + CURRENT, lane], wb[o + TRACTION, lane] = current[i, j], traction[i, j]


@njit(cache=True, error_model="numpy")
def _store(rb: FloatArray, wb: FloatArray, first: int, n: int, m: int, views: tuple[FloatArray, ...]) -> None:
    """Copy the state of a block back into robots first.. of the packed state."""
    pose, q, wheel_angle, current, traction, battery = views[:6]
    for lane in range(min(BLOCK, n - first)):
        i = first + lane
        pose[i, 0], pose[i, 1], pose[i, 2] = rb[X, lane], rb[Y, lane], rb[TH, lane]
        q[i, 0], q[i, 1], q[i, 2] = rb[VX, lane], rb[VY, lane], rb[W, lane]
        battery[i, 0], battery[i, 1] = rb[V_BUS, lane], rb[I_BATT, lane]
        for j in range(m):
            o = j * WHEEL_ROWS
            q[i, 3 + j], wheel_angle[i, j] = wb[o + OMEGA, lane], wb[o + ANGLE, lane]
            current[i, j], traction[i, j] = wb[o + CURRENT, lane], wb[o + TRACTION, lane]


@njit(cache=True, inline="always", error_model="numpy")
def _begin(rb: FloatArray) -> None:
    """Each robot's bus voltage after its battery's relaxation, its body system and current sum
    cleared."""
    for i in range(BLOCK):
        v_bus = rb[V_BUS, i]
        v_bus = v_bus + rb[B_RELAX, i] * (rb[V_OPEN, i] - rb[B_RES, i] * rb[I_BATT, i] - v_bus)
        rb[V_BUS, i] = max(v_bus, 0.0)
        rb[S00, i], rb[S11, i], rb[S22, i] = rb[M_DT, i], rb[M_DT, i], rb[I_DT, i]
        rb[S01, i] = rb[S02, i] = rb[S12, i] = 0.0
        rb[R0, i] = rb[R1, i] = rb[R2, i] = 0.0
        rb[I_SUM, i] = 0.0


@njit(cache=True, inline="always", error_model="numpy")
def _heading_sincos(rb: FloatArray) -> None:
    """The sine and cosine of each robot's heading (ARG), which turn the world force into its body
    frame."""
    far = 0
    for i in range(BLOCK):
        rb[ARG, i] = rb[TH, i]
        rb[SIN, i], rb[COS, i] = sincos(rb[TH, i])
        far += _far(rb[TH, i])
    if far:
        _fix_range(rb, ARG, SIN, COS)


@njit(cache=True, inline="always", error_model="numpy")
def _roller_cos(wb: FloatArray, o: int) -> None:
    """The cosine of the roller phase (roller count times wheel angle) of the wheel at row o."""
    far = 0
    for i in range(BLOCK):
        wb[o + WARG, i] = wb[o + COUNT, i] * wb[o + ANGLE, i]
        wb[o + WCOS, i] = cos(wb[o + WARG, i])
        far += _far(wb[o + WARG, i])
    if far:
        _fix_range(wb, o + WARG, -1, o + WCOS)


@njit(cache=True, inline="always", error_model="numpy")
def _motor(wb: FloatArray, o: int, i: int, v_bus: float, omega: float) -> tuple[float, float, float]:
    """Driver and motor of the wheel at row o of lane i: (duty, current, the back-EMF's damping when
    the current follows it, not limited, else 0)."""
    duty = wb[o + DUTY, i]
    i_free = duty * (max(v_bus - wb[o + DROP, i], 0.0) * wb[o + INV_RES, i]) - wb[o + KE_RES, i] * omega
    i_max = wb[o + I_MAX, i]
    on = wb[o + ON, i] != 0.0
    amps = min(max(i_free, -i_max), i_max) if on else 0.0
    emf = wb[o + EMF, i] if on and abs(i_free) < i_max else 0.0
    return duty, amps, emf


@njit(cache=True, inline="always", error_model="numpy")
def _friction(wb: FloatArray, o: int, i: int, slip: float, roll: float, omega: float) -> Forces:
    """Friction forces and secant slopes on the three contact rows of the wheel at row o of lane i
    (traction ft, kt; rolling fn, kn; axle fa, ka), with the scrub (selected, not branched)."""
    inv_veps = wb[o + INV_VEPS, i]
    roll_max = (wb[o + RR_TOP, i] - wb[o + RR_VAR, i] * wb[o + WCOS, i]) * wb[o + ROLL_LOAD, i]
    ft, kt = _secant(wb[o + F_TRACTION, i], inv_veps, slip * inv_veps)
    fn, kn = _secant(roll_max, _INV_ROLL_EPS, roll * _INV_ROLL_EPS)
    fa, ka = _secant(wb[o + STATIC, i], _INV_WHEEL_EPS, omega * _INV_WHEEL_EPS)
    radius, scrub_load = wb[o + RADIUS, i], wb[o + SCRUB, i]
    rim = radius * omega
    both = rim * rim + roll * roll
    scrubs = scrub_load > 0.0 and both > 1e-12
    scrub = scrub_load * 2.0 * abs(rim) * abs(roll) / both if scrubs else 0.0
    fn = fn + scrub * roll if scrubs else fn
    kn = kn + scrub if scrubs else kn
    fa = fa + scrub * radius * rim if scrubs else fa
    ka = ka + scrub * radius * radius if scrubs else ka
    return ft, kt, fn, kn, fa, ka


@njit(cache=True, inline="always", error_model="numpy")
def _eliminate(rb: FloatArray, wb: FloatArray, o: int, i: int, forces: Forces) -> None:
    """The rows of the wheel at row o of lane i added to its robot's body system, the wheel's speed
    eliminated (its factors into wb's E0, E1, E2, INV_D, RW)."""
    ft, kt, fn, kn, fa, ka = forces
    tx, ty, tw, ta = wb[o + TX, i], wb[o + TY, i], wb[o + TW, i], wb[o + TA, i]
    nx, ny, nw, na = wb[o + NX, i], wb[o + NY, i], wb[o + NW, i], wb[o + NA, i]
    rb[R0, i] -= ft * tx + fn * nx
    rb[R1, i] -= ft * ty + fn * ny
    rb[R2, i] -= ft * tw + fn * nw
    rw = -(ft * ta + fn * na + fa)
    rb[S00, i] += kt * tx * tx + kn * nx * nx
    rb[S11, i] += kt * ty * ty + kn * ny * ny
    rb[S22, i] += kt * tw * tw + kn * nw * nw
    rb[S01, i] += kt * tx * ty + kn * nx * ny
    rb[S02, i] += kt * tx * tw + kn * nx * nw
    rb[S12, i] += kt * ty * tw + kn * ny * nw
    c0 = kt * ta * tx + kn * na * nx
    c1 = kt * ta * ty + kn * na * ny
    c2 = kt * ta * tw + kn * na * nw
    inv_d = 1.0 / (wb[o + J_DT, i] + kt * ta * ta + kn * na * na + ka)
    e0, e1, e2 = c0 * inv_d, c1 * inv_d, c2 * inv_d
    rb[S00, i] -= c0 * e0
    rb[S11, i] -= c1 * e1
    rb[S22, i] -= c2 * e2
    rb[S01, i] -= c0 * e1
    rb[S02, i] -= c0 * e2
    rb[S12, i] -= c1 * e2
    rb[R0, i] -= e0 * rw
    rb[R1, i] -= e1 * rw
    rb[R2, i] -= e2 * rw
    wb[o + E0, i], wb[o + E1, i], wb[o + E2, i] = e0, e1, e2
    wb[o + INV_D, i], wb[o + RW, i] = inv_d, rw


@njit(cache=True, inline="always", error_model="numpy")
def _wheel(rb: FloatArray, wb: FloatArray, o: int) -> None:
    """The wheel at row o of every lane: its motor's current, its friction, its rows eliminated into
    the body system."""
    _roller_cos(wb, o)
    for i in range(BLOCK):
        vx, vy, w, v_bus = rb[VX, i], rb[VY, i], rb[W, i], rb[V_BUS, i]
        omega = wb[o + OMEGA, i]
        duty, amps, emf = _motor(wb, o, i, v_bus, omega)
        slip = wb[o + TX, i] * vx + wb[o + TY, i] * vy + wb[o + TW, i] * w + wb[o + TA, i] * omega
        roll = wb[o + NX, i] * vx + wb[o + NY, i] * vy + wb[o + NW, i] * w + wb[o + NA, i] * omega
        ft, kt, fn, kn, fa, ka = _friction(wb, o, i, slip, roll, omega)
        fa -= wb[o + KT, i] * amps - wb[o + VISC, i] * omega
        ka += emf + wb[o + VISC, i]
        wb[o + TRACTION, i] = -ft
        wb[o + CURRENT, i] = amps
        rb[I_SUM, i] += duty * amps
        _eliminate(rb, wb, o, i, (ft, kt, fn, kn, fa, ka))


@njit(cache=True, inline="always", error_model="numpy")
def _solve(rb: FloatArray, has_ext: bool, dt: float) -> int:
    """Each robot's body system solved, with the world force in the body frame: its speed change
    into R0, R1, R2, its twist updated, the angles of its rotation (ARG) and mid-step heading (ARG2)
    with their sines and cosines. Returns how many of those angles are past :func:`sincos`'s range."""
    far = 0
    for i in range(BLOCK):
        r0, r1, r2 = rb[R0, i], rb[R1, i], rb[R2, i]
        if has_ext:  # world force and torque, into the body frame
            c, s = rb[COS, i], rb[SIN, i]
            r0 += c * rb[EXT_X, i] + s * rb[EXT_Y, i]
            r1 += c * rb[EXT_Y, i] - s * rb[EXT_X, i]
            r2 += rb[EXT_T, i]
        dvx, dvy, dw = solve_body(
            rb[S00, i], rb[S11, i], rb[S22, i], rb[S01, i], rb[S02, i], rb[S12, i], r0, r1, r2
        )
        rb[R0, i], rb[R1, i], rb[R2, i] = dvx, dvy, dw  # the body's speed change
        rb[VX, i], rb[VY, i], rb[W, i] = rb[VX, i] + dvx, rb[VY, i] + dvy, rb[W, i] + dw
        w = rb[W, i]
        rb[ARG, i] = w * dt
        rb[SIN, i], rb[COS, i] = sincos(w * dt)
        rb[ARG2, i] = rb[TH, i] + 0.5 * dt * w
        rb[SIN2, i], rb[COS2, i] = sincos(rb[ARG2, i])
        far += _far(rb[ARG, i]) + _far(rb[ARG2, i])
    return far


@njit(cache=True, inline="always", error_model="numpy")
def _advance(rb: FloatArray, wb: FloatArray, m: int, dt: float) -> None:
    """The wheels' speeds and angles after the bodies' speed changes (R0, R1, R2), then each body's
    velocity rotated by -w dt and its pose moved at the mid-step heading."""
    for j in range(m):
        o = j * WHEEL_ROWS
        for i in range(BLOCK):
            wb[o + OMEGA, i] += (
                wb[o + RW, i] * wb[o + INV_D, i] - wb[o + E0, i] * rb[R0, i] - wb[o + E1, i] * rb[R1, i]
                - wb[o + E2, i] * rb[R2, i]
            )  # fmt: skip
            wb[o + ANGLE, i] += dt * wb[o + OMEGA, i]
    for i in range(BLOCK):
        # body-frame rotation of the velocity by -w dt, pose at the mid-step heading
        c, s = rb[COS, i], rb[SIN, i]
        vx, vy, w = rb[VX, i], rb[VY, i], rb[W, i]
        vx, vy = vx * c + vy * s, vy * c - vx * s
        rb[VX, i], rb[VY, i] = vx, vy
        c, s = rb[COS2, i], rb[SIN2, i]
        rb[X, i] += (c * vx - s * vy) * dt
        rb[Y, i] += (s * vx + c * vy) * dt
        rb[TH, i] += dt * w
        rb[I_BATT, i] = rb[I_SUM, i]


@njit(cache=True, inline="always", error_model="numpy")
def _step(rb: FloatArray, wb: FloatArray, m: int, has_ext: bool, dt: float) -> None:
    """Advance the robots of a block (``rb`` per robot, ``wb`` per wheel) by dt: the operations of
    :func:`omnibot.sim.kernels.wheels.robot_physics` in the same order, over the block's lanes (each loop
    over lanes vectorises; the C library's sin and cos only where a loop met an angle too large)."""
    _begin(rb)
    if has_ext:
        _heading_sincos(rb)
    for j in range(m):
        _wheel(rb, wb, j * WHEEL_ROWS)
    if _solve(rb, has_ext, dt):
        _fix_range(rb, ARG, SIN, COS)
        _fix_range(rb, ARG2, SIN2, COS2)
    _advance(rb, wb, m, dt)


@njit(cache=True, inline="always", error_model="numpy")
def _secant(fmax: float, inv_eps: float, x: float) -> tuple[float, float]:
    """:func:`omnibot.sim.kernels.wheels._secant` with :func:`tanh` (x = 0: the slope's limit, no branch)."""
    th = tanh(x)
    ratio = th / x if x != 0.0 else 1.0
    return fmax * th, fmax * inv_eps * ratio


@njit(cache=True, parallel=True, error_model="numpy")
def physics_run(
    buf: FloatArray, ids: IntArray, n: int, m: int, n_surf: int, has_ext: bool, dt: float, steps: int
) -> int:
    """:func:`~omnibot.sim.kernels.physics_step_parallel` with robots in vector lanes and this
    module's tanh, sin and cos: ``steps`` steps of every robot of the packed state ``buf``, blocks
    of :data:`BLOCK` robots shared out among numba's threads. Returns 0, or 1 (state untouched)
    if a surface id is out of range."""
    views = physics_views(buf, n, m, n_surf)
    for i in range(n):
        for j in range(m):
            if ids[i, j] < 0 or ids[i, j] >= n_surf:
                return 1
    for block in prange((n + BLOCK - 1) // BLOCK):
        rb = np.empty((ROBOT_ROWS, BLOCK))
        wb = np.empty((m * WHEEL_ROWS, BLOCK))
        _load(rb, wb, block * BLOCK, n, m, views, ids)
        for _ in range(steps):
            _step(rb, wb, m, has_ext, dt)
        _store(rb, wb, block * BLOCK, n, m, views)
    return 0


def fill_cache() -> None:
    """Compile :func:`physics_run` into numba's disk cache (``make setup``), so a batch's first
    ``exact=False`` run, and the tests', only load it (the call steps no robot: types alone decide
    what is compiled)."""
    n, m, n_surf = 1, 4, 1
    buf = np.zeros(physics_offsets.py_func(n, m, n_surf)[-1])
    physics_run(buf, np.zeros((n, m), dtype=np.int64), n, m, n_surf, False, 0.001, 0)


if __name__ == "__main__":  # make setup
    fill_cache()
