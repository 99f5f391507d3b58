"""The laser scanner's kernels: an index of the edges by direction, the rays cast through it
against the world and the other bodies, and the measurement's noise.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from omnibot.sim.kernels.contacts import segment_distance
from omnibot.sim.kernels.layout import (
    I_LOG_CAP,
    I_LOG_DT,
    I_LOG_FLUSH,
    I_LOG_N,
    I_LOG_NEXT,
    I_LOG_STRIDE,
    STEP_SCAN,
    FloatArray,
    IntArray,
    sim_offsets,
)
from omnibot.sim.kernels.scan_noise import scan_measure
from omnibot.sim.kernels.scan_ray import RAY_T, bracket, lerp, ray_frame, ray_table

SCAN_BINS = 256
"""Directions of a :func:`scan_index`: the circle is cut into this many equal sectors."""

# scan_revolution's parameters (one float64 array): the pose history's start and step, the mount, the
# cast's reach, the edge index's disc (centre, and how far the origins may lie from it: < 0, no
# index), the measurement's noise and limits (scan_measure's)
P_T0, P_DT, P_MOUNT_X, P_MOUNT_Y, P_REACH, P_AX, P_AY, P_INNER = 0, 1, 2, 3, 4, 5, 6, 7
P_NOISE_STD, P_NOISE_FRACTION, P_RESOLUTION, P_DROPOUT, P_RANGE_MIN, P_RANGE_MAX = 8, 9, 10, 11, 12, 13
SCAN_PARAMS = 14


@njit(cache=True)
def pose_log(sf: FloatArray, si: IntArray, x: float, y: float, th: float, now_us: int) -> int:
    """Record (x, y, th), the pose at the end of the step that began at ``now_us``, as the next row of
    the simulator's pose log when that end is at or after I_LOG_NEXT (the ``I_LOG_`` columns of
    :mod:`~omnibot.sim.kernels.layout`); STEP_SCAN if it did and the end is at or after I_LOG_FLUSH
    (the scanner is due), else 0. A row past the log's capacity is counted, not written (whoever
    reads the log raises)."""
    end = now_us + si[I_LOG_DT]
    if end < si[I_LOG_NEXT]:
        return 0
    n = si[I_LOG_N]
    if n < si[I_LOG_CAP]:
        o = sim_offsets(si)[4] + 3 * n
        sf[o], sf[o + 1], sf[o + 2] = x, y, th
    si[I_LOG_N] = n + 1
    si[I_LOG_NEXT] += si[I_LOG_STRIDE]
    return STEP_SCAN if end >= si[I_LOG_FLUSH] else 0


@njit(cache=True)
def _turn(a: float) -> float:
    """a wrapped to [0, 2 pi)."""
    return a - 2.0 * math.pi * math.floor(a / (2.0 * math.pi))


@njit(cache=True)
def _hit(ox: float, oy: float, dx: float, dy: float, x0: float, y0: float, x1: float, y1: float) -> float:
    """Distance along the ray (ox, oy) + t (dx, dy) to the edge (x0, y0)-(x1, y1), inf if it misses.

    The edge's parameter u = un / denom must lie in [0, 1]: tested as un against 0 and denom, which
    a correctly rounded division orders alike (so no division for an edge the ray passes beside)."""
    ex, ey = x1 - x0, y1 - y0
    denom = dx * ey - dy * ex
    if abs(denom) < 1e-12:
        return np.inf
    ax, ay = x0 - ox, y0 - oy
    un = ax * dy - ay * dx
    if (un < 0.0 or un > denom) if denom > 0.0 else (un > 0.0 or un < denom):
        return np.inf
    t = (ax * ey - ay * ex) / denom
    return t if t >= 0.0 else np.inf


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
    px1 = py1 = a1 = np.nan  # the last end point whose angle was found, and that angle
    for e in range(n_seg):
        x0, y0, x1, y1 = segments[e, 0], segments[e, 1], segments[e, 2], segments[e, 3]
        d = segment_distance(ax, ay, x0, y0, x1, y1)
        if d - radius > max_range:
            continue
        near[e] = d - radius
        if d <= radius:
            count[e] = SCAN_BINS
            continue
        # an outline's edge starts where the one before it ended: that angle is known
        a0 = a1 if x0 == px1 and y0 == py1 else math.atan2(y0 - ay, x0 - ax)
        px1, py1, a1 = x1, y1, math.atan2(y1 - ay, x1 - ax)
        span = _wrap(a1 - a0)
        if span < 0.0:
            a0, span = a0 + span, -span
        widen = math.asin(min(1.0, radius / d)) + 1e-9
        a0, span = _turn(a0 - widen), span + 2.0 * widen
        lo = min(int(a0 / width), SCAN_BINS - 1)
        first[e] = lo
        count[e] = min(int((a0 + span) / width) - lo + 1, SCAN_BINS)
    order = np.argsort(near)
    starts = np.zeros(SCAN_BINS + 1, dtype=np.int64)
    # each sector's count: edge e covers first[e] to first[e] + count[e] - 1 on a doubled circle
    # (differences summed up), sector b being b and b + SCAN_BINS there
    cover = np.zeros(2 * SCAN_BINS + 1, dtype=np.int64)
    for e in range(n_seg):
        cover[first[e]] += 1
        cover[first[e] + count[e]] -= 1
    for b in range(2 * SCAN_BINS):
        cover[b + 1] += cover[b]
    for b in range(SCAN_BINS):
        starts[b + 1] = starts[b] + cover[b] + cover[b + SCAN_BINS]
    fill = starts[:-1].copy()
    entries = np.empty(starts[SCAN_BINS], dtype=np.int64)
    for q in range(n_seg):  # sector b of edge e: first[e] + k, wrapped by a subtraction, not a modulo
        e = order[q]
        for k in range(count[e]):
            b = first[e] + k
            b = b - SCAN_BINS if b >= SCAN_BINS else b
            entries[fill[b]] = e
            fill[b] += 1
    return starts, entries, near


@njit(cache=True)
def scan_index_around(
    segments: FloatArray, hist_p: FloatArray, own: int, reach: float, slack: float, max_range: float,
    params: FloatArray,
) -> tuple[IntArray, IntArray, FloatArray]:  # fmt: skip
    """:func:`scan_index` for a scanner ``reach`` from the origin of body ``own`` anywhere it was over
    the rows of ``hist_p``, with ``slack`` to spare: the disc about their mean that holds them all,
    widened by reach and slack; the disc's centre and how far the robot may go from it (its radius
    less reach) into params[P_AX], params[P_AY], params[P_INNER] (:func:`scan_revolution`'s)."""
    c0 = 3 * own
    n = hist_p.shape[0]
    ax = ay = 0.0
    for j in range(n):
        ax, ay = ax + hist_p[j, c0], ay + hist_p[j, c0 + 1]
    ax, ay = ax / n, ay / n
    spread = 0.0
    for j in range(n):
        spread = max(spread, math.hypot(hist_p[j, c0] - ax, hist_p[j, c0 + 1] - ay))
    radius = spread + reach + slack
    params[P_AX], params[P_AY], params[P_INNER] = ax, ay, radius - reach
    return scan_index(segments, ax, ay, radius, max_range)


@njit(cache=True)
def _wrap(a: float) -> float:
    """a wrapped to [-pi, pi)."""
    return a - 2.0 * math.pi * math.floor((a + math.pi) / (2.0 * math.pi))


@njit(cache=True, inline="always")
def _body_radii(body_v: FloatArray, body_off: IntArray) -> FloatArray:
    """Each body's bounding radius about its own origin (body b: body_v[body_off[b]:body_off[b+1]])."""
    n_body = body_off.shape[0] - 1
    body_r = np.zeros(n_body)
    for b in range(n_body):
        for v in range(body_off[b], body_off[b + 1]):
            body_r[b] = max(body_r[b], math.hypot(body_v[v, 0], body_v[v, 1]))
    return body_r


@njit(cache=True, inline="always")
def _outline_hit(
    rx: float, ry: float, dx: float, dy: float, bt: float, body_v: FloatArray, v0: int, v1: int, best: float
) -> float:
    """``best``, or the distance along the ray (direction dx, dy) to the closed outline
    body_v[v0:v1] of a body at heading bt whose origin is (rx, ry) from the ray's, if nearer."""
    cbt, sbt = math.cos(bt), math.sin(bt)
    px, py = -cbt * rx - sbt * ry, sbt * rx - cbt * ry  # the origin in the body's frame
    qx, qy = cbt * dx + sbt * dy, -sbt * dx + cbt * dy  # the direction in the body's frame
    for v in range(v0, v1):
        w = v + 1 if v + 1 < v1 else v0
        t = _hit(px, py, qx, qy, body_v[v, 0], body_v[v, 1], body_v[w, 0], body_v[w, 1])
        best = min(best, t)
    return best


@njit(cache=True, inline="always")
def _body_hit(
    hist_p: FloatArray, k: int, k1: int, f: float, cb: int, ox: float, oy: float, dx: float, dy: float,
    r: float, body_v: FloatArray, v0: int, v1: int, best: float,
) -> float:  # fmt: skip
    """``best``, or the distance along the ray from (ox, oy) in direction (dx, dy) to the outline
    body_v[v0:v1] (bounding radius r) of the body whose pose is history columns cb..cb+2, a
    fraction f from row k to k1, if nearer."""
    rx, ry = lerp(hist_p, k, k1, f, cb) - ox, lerp(hist_p, k, k1, f, cb + 1) - oy
    along = rx * dx + ry * dy
    if along + r < 0.0 or along - r > best or abs(rx * dy - ry * dx) > r:
        return best  # its bounding circle is behind, beyond the best hit or beside the ray
    bt = lerp(hist_p, k, k1, f, cb + 2)
    return _outline_hit(rx, ry, dx, dy, bt, body_v, v0, v1, best)


@njit(cache=True, inline="always")
def _cast_rays(
    stamp: float, first: int, last: int, rays: FloatArray, hist_t0: float, hist_dt: float, hist_p: FloatArray,
    own: int, mount_x: float, mount_y: float, segments: FloatArray, starts: IntArray, entries: IntArray,
    near: FloatArray, body_v: FloatArray, body_off: IntArray, max_range: float, out: FloatArray,
) -> None:  # fmt: skip
    """Rays ``first`` to ``last - 1`` of ``rays`` (ray i at time stamp + rays[i, RAY_T]) cast into
    out, as :func:`scan_rays` describes (the cos and sin of a history row's heading once per row)."""
    body_r = _body_radii(body_v, body_off)
    c0, row, ck, sk = 3 * own, -1, 1.0, 0.0
    for i in range(first, last):
        k, k1, f = bracket(stamp + rays[i, RAY_T], hist_t0, hist_dt, hist_p.shape[0])
        if k != row:
            row, ck, sk = k, math.cos(hist_p[k, c0 + 2]), math.sin(hist_p[k, c0 + 2])
        ox, oy, ang, dx, dy = ray_frame(hist_p, k, k1, f, c0, ck, sk, mount_x, mount_y, rays, i)
        # its sector by multiplying, not dividing: a ray on a sector's border may be given either one,
        # and either lists every edge it can meet (scan_index widens each edge's angles by 1e-9 rad)
        turns = ang * (0.5 / math.pi)
        sector = min(int((turns - math.floor(turns)) * SCAN_BINS), SCAN_BINS - 1)
        best = np.inf
        for q in range(starts[sector], starts[sector + 1]):  # here, not in a helper: 30 % faster
            e = entries[q]
            if near[e] > best:
                break
            t = _hit(ox, oy, dx, dy, segments[e, 0], segments[e, 1], segments[e, 2], segments[e, 3])
            best = min(best, t)
        for b in range(body_off.shape[0] - 1):
            if b != own:
                best = _body_hit(
                    hist_p, k, k1, f, 3 * b, ox, oy, dx, dy, body_r[b], body_v, body_off[b], body_off[b + 1], best
                )  # fmt: skip
        out[i] = best if best <= max_range else np.inf


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
    rays = ray_table(ray_t, ray_a)
    _cast_rays(
        0.0, 0, rays.shape[0], rays, hist_t0, hist_dt, hist_p, own, mount_x, mount_y, segments, starts, entries,
        near, body_v, body_off, max_range, out,
    )  # fmt: skip


@njit(cache=True)
def _index_holds(hist_p: FloatArray, c0: int, ax: float, ay: float, inner: float) -> bool:
    """Whether every origin of history columns c0, c0 + 1 lies within ``inner`` of (ax, ay)."""
    if not inner > 0.0:
        return False
    for j in range(hist_p.shape[0]):
        dx, dy = hist_p[j, c0] - ax, hist_p[j, c0 + 1] - ay
        if dx * dx + dy * dy > inner * inner:
            return False
    return True


@njit(cache=True)
def scan_revolution(
    stamp: float,
    first: int,
    last: int,
    rays: FloatArray,
    hist_p: FloatArray,
    own: int,
    params: FloatArray,
    segments: FloatArray,
    starts: IntArray,
    entries: IntArray,
    near: FloatArray,
    body_v: FloatArray,
    body_off: IntArray,
    true: FloatArray,
    normals: FloatArray,
    uniforms: FloatArray,
    measured: FloatArray,
) -> bool:
    """Rays ``first`` to ``last - 1`` of the revolution that began at ``stamp`` (ray i measured at
    stamp + rays[i, RAY_T] in direction rays[i, RAY_A] of the robot's base frame: :func:`ray_table`)
    cast as :func:`scan_rays` casts them (the ``P_`` columns of ``params``) into true[first:last];
    then, given its ``normals`` and ``uniforms`` (one of each per ray; none: the revolution goes
    on), the whole revolution measured from ``true`` into ``measured`` (:func:`scan_measure`). The scanner's
    origins over the rows of ``hist_p`` must lie within params[P_INNER] of (params[P_AX],
    params[P_AY]), the disc the edge index holds: else nothing is done and False returned (the
    caller builds an index for them and calls again)."""
    if not _index_holds(hist_p, 3 * own, params[P_AX], params[P_AY], params[P_INNER]):
        return False
    _cast_rays(
        stamp, first, last, rays, params[P_T0], params[P_DT], hist_p, own, params[P_MOUNT_X], params[P_MOUNT_Y],
        segments, starts, entries, near, body_v, body_off, params[P_REACH], true,
    )  # fmt: skip
    if normals.shape[0]:
        scan_measure(
            true, normals, uniforms, params[P_NOISE_STD], params[P_NOISE_FRACTION], params[P_RESOLUTION], params[P_DROPOUT],
            params[P_RANGE_MIN], params[P_RANGE_MAX], measured,
        )  # fmt: skip
    return True
