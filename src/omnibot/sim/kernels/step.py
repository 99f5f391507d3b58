"""One robot's whole step in one compiled call, and a fleet's.

:func:`robot_step` is one :class:`~omnibot.sim.simulator.Simulator` step whole: surfaces,
contacts and their forces, extra forces, the physics, the gyro and tracking wheels. Its state
comes packed, as numba's dispatch costs about 0.1 us per array argument
(:mod:`omnibot.sim.kernels.layout`); :func:`robot_before` and :func:`robot_after` are its parts
around a physics of another kind; :func:`fleet_step` is :func:`robot_step` for every robot of a
fleet in one call, their arrays views of the fleet's buffers (:mod:`omnibot.sim.fleet_arrays`).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from omnibot.sim.kernels.contacts import outline_contacts, surface_probe
from omnibot.sim.kernels.layout import (
    F_AT_TH,
    F_AT_X,
    F_AT_Y,
    F_CLEAR,
    F_CLEAR_X,
    F_CLEAR_Y,
    F_DAMPING,
    F_INERTIA,
    F_MASS,
    F_OMEGA,
    F_REACH,
    F_SURF_CLEAR,
    F_SURF_TH,
    F_SURF_X,
    F_SURF_Y,
    F_WALL_FRICTION,
    G_NEXT,
    G_PERIOD,
    I_C,
    I_COUNT,
    I_LOG_ON,
    I_M,
    I_PATCHY,
    I_RELEASE,
    I_V,
    I_WALLS,
    L_EXTRA,
    L_GYRO,
    L_GYRO_END,
    L_GYRO_NORMALS,
    L_GYRO_NORMALS_END,
    L_IDS,
    L_M,
    L_N_EXTRA,
    L_N_SURF,
    L_PBUF,
    L_PBUF_END,
    L_SF,
    L_SF_END,
    L_SI,
    L_SI_END,
    L_TRACKING,
    L_TRACKING_END,
    L_TRACKING_NORMALS,
    L_TRACKING_NORMALS_END,
    NEVER,
    STEP_BAD_SURFACE,
    STEP_COLLISION,
    STEP_FORCE,
    STEP_REFILL,
    T_HEADER,
    T_NEXT,
    FloatArray,
    IntArray,
    physics_views,
    sim_offsets,
    world_offsets,
)
from omnibot.sim.kernels.scan import pose_log
from omnibot.sim.kernels.sensors import gyro_update, tracking_update
from omnibot.sim.kernels.wheels import ids_valid, robot_physics


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


@njit(cache=True, inline="always")
def _floor_ids(
    x: float, y: float, th: float, ids: IntArray, wf: FloatArray, wi: IntArray, sf: FloatArray, si: IntArray
) -> None:
    """The floor's surface id under each wheel into ids, when the robot moved far enough since the
    last lookup that a wheel may have changed patch (and the lookup's pose and clearance into sf)."""
    _, _, _, of3, _, _, _, _, oi2, oi3, _ = sim_offsets(si)
    m = si[I_M]
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


@njit(cache=True, inline="always")
def _wall_forces(
    x: float, y: float, th: float, vx: float, vy: float, w: float,
    wf: FloatArray, wi: IntArray, sf: FloatArray, si: IntArray, now_us: int,
) -> tuple[float, float, float, int]:  # fmt: skip
    """The world's push-back on the body (fx, fy, tz, world frame) and STEP_COLLISION when a contact
    is fresh; the contacts are looked up again only once the robot left their clearance."""
    of0, of1, of2, _, _, _, oi0, oi1, _, _, _ = sim_offsets(si)
    status = 0
    fx = fy = tz = 0.0
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
    return fx, fy, tz, status


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
    status = 0
    if si[I_PATCHY]:
        _floor_ids(x, y, th, ids, wf, wi, sf, si)
    fx = fy = tz = 0.0
    if si[I_WALLS]:
        fx, fy, tz, status = _wall_forces(x, y, th, vx, vy, w, wf, wi, sf, si, now_us)
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
    (rows added in order), the physics (state packed in ``pbuf``: :func:`physics_views`), the pose
    log of the laser scanners (:func:`~omnibot.sim.kernels.scan.pose_log`, while it is on), and the
    gyro and tracking wheels. Returns the STEP_ status bits (STEP_BAD_SURFACE: nothing moved)."""
    pose, q, wheel_angle, current, traction, battery, v_open, pwm, ext, wp, rp, surf = physics_views(
        pbuf, 1, m, n_surf
    )
    x, y, th = pose[0, 0], pose[0, 1], pose[0, 2]
    vx0, vy0, w0 = q[0, 0], q[0, 1], q[0, 2]
    status = _before_physics(x, y, th, vx0, vy0, w0, ids, wf, wi, sf, si, extra, n_extra, ext, now_us)
    if not ids_valid(ids, n_surf):
        return status | STEP_BAD_SURFACE
    scratch = np.empty((m, 5))
    has_ext = status & STEP_FORCE != 0
    robot_physics(
        0, pose, q, wheel_angle, current, traction, battery, v_open, pwm, ids, ext, has_ext, wp, rp, surf, dt,
        scratch,
    )  # fmt: skip
    if si[I_LOG_ON]:
        status |= pose_log(sf, si, pose[0, 0], pose[0, 1], pose[0, 2], now_us)
    return status | _after_physics(
        vx0, vy0, w0, q[0, 0], q[0, 1], q[0, 2], dt, gyro, gyro_normals, tracking, tracking_normals
    )


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
