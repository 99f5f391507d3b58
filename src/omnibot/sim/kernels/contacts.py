"""The world's contact geometry: the floor surface under points, an outline's contacts with walls
and obstacles (separating axes), and a sonar cone's nearest edge.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from omnibot.sim.kernels.layout import FloatArray, IntArray

MERGE_COS = math.cos(math.radians(30.0))
"""Edge contacts of one owner whose normals are closer than 30 degrees are merged."""


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
def segment_distance(px: float, py: float, x0: float, y0: float, x1: float, y1: float) -> float:
    """Distance from (px, py) to the segment (x0, y0)-(x1, y1)."""
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
                d = segment_distance(px, py, verts[e, 0], verts[e, 1], verts[e1, 0], verts[e1, 1])
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


@njit(cache=True, inline="always")
def _centroid(v: FloatArray, lo: int, hi: int) -> tuple[float, float]:
    """The mean of the vertices v[lo:hi]."""
    cx = cy = 0.0
    for k in range(lo, hi):
        cx += v[k, 0]
        cy += v[k, 1]
    return cx / (hi - lo), cy / (hi - lo)


@njit(cache=True, inline="always")
def _overlap(
    robot: FloatArray, other: FloatArray, lo: int, hi: int, ax: float, ay: float
) -> tuple[float, float]:
    """How far the robot must move along +axis and along -axis to clear other[lo:hi] on that axis
    (one of them not positive: the axis separates them)."""
    rmin, rmax, omin, omax = np.inf, -np.inf, np.inf, -np.inf
    for k in range(robot.shape[0]):
        pr = robot[k, 0] * ax + robot[k, 1] * ay
        rmin, rmax = min(rmin, pr), max(rmax, pr)
    for k in range(lo, hi):
        po = other[k, 0] * ax + other[k, 1] * ay
        omin, omax = min(omin, po), max(omax, po)
    return omax - rmin, rmax - omin


@njit(cache=True, inline="always")
def _shallowest(
    robot: FloatArray, other: FloatArray, lo: int, hi: int, axes: FloatArray, count: int, depth: FloatArray
) -> tuple[bool, float]:
    """(overlap, shallowest depth): the robot's way out along each of the count axes into depth
    (depth, sign: toward the robot's side of the axis), unless an axis separates the shapes."""
    crx, cry = _centroid(robot, 0, robot.shape[0])
    cox, coy = _centroid(other, lo, hi)
    best = np.inf
    for a in range(count):
        ax, ay = axes[a, 0], axes[a, 1]
        plus, minus = _overlap(robot, other, lo, hi, ax, ay)  # move the robot along +axis / -axis to clear
        if plus <= 0.0 or minus <= 0.0:
            return False, best
        side = (crx - cox) * ax + (cry - coy) * ay
        if side > 1e-12:
            dep, sign = plus, 1.0
        elif side < -1e-12:
            dep, sign = minus, -1.0
        else:
            dep, sign = min(plus, minus), (1.0 if plus <= minus else -1.0)
        depth[a, 0], depth[a, 1] = dep, sign
        best = min(best, dep)
    return True, best


@njit(cache=True, inline="always")
def _face_span(
    v: FloatArray, lo: int, hi: int, nx: float, ny: float, limit: float, below: bool
) -> tuple[float, float, float, int]:
    """(lowest, highest, sum, count) of the positions along the face (tangent (-ny, nx)) of the
    vertices of v[lo:hi] at the deepest feature: projected on the normal no higher (``below``) or
    no lower than limit."""
    tx, ty = -ny, nx
    f_lo, f_hi, f_sum, f_n = np.inf, -np.inf, 0.0, 0
    for j in range(lo, hi):
        p = v[j, 0] * nx + v[j, 1] * ny
        if (p <= limit) if below else (p >= limit):
            f = v[j, 0] * tx + v[j, 1] * ty
            f_lo, f_hi, f_sum, f_n = min(f_lo, f), max(f_hi, f), f_sum + f, f_n + 1
    return f_lo, f_hi, f_sum, f_n


@njit(cache=True, inline="always")
def _contact_point(
    robot: FloatArray, other: FloatArray, lo: int, hi: int, nx: float, ny: float, best: float
) -> tuple[float, float]:
    """The contact point along normal (nx, ny): the middle of the overlap, along the face, of the
    two deepest features."""
    nr = robot.shape[0]
    tx, ty = -ny, nx
    tol = 1e-6 + 1e-3 * best
    pr_min, po_max = np.inf, -np.inf
    for j in range(nr):
        pr_min = min(pr_min, robot[j, 0] * nx + robot[j, 1] * ny)
    for j in range(lo, hi):
        po_max = max(po_max, other[j, 0] * nx + other[j, 1] * ny)
    r_lo, r_hi, r_sum, r_n = _face_span(robot, 0, nr, nx, ny, pr_min + tol, True)
    o_lo, o_hi, o_sum, o_n = _face_span(other, lo, hi, nx, ny, po_max - tol, False)
    lo_f, hi_f = max(r_lo, o_lo), min(r_hi, o_hi)
    along = 0.5 * (lo_f + hi_f) if lo_f <= hi_f else 0.5 * (r_sum / r_n + o_sum / o_n)
    across = 0.5 * (pr_min + po_max)
    return along * tx + across * nx, along * ty + across * ny


@njit(cache=True)
def _sat(
    robot: FloatArray, other: FloatArray, lo: int, hi: int, closed: bool, axes: FloatArray, depth: FloatArray
) -> tuple[bool, float, float, float, float, float]:
    """Separating-axis test of the convex robot outline against the convex other[lo:hi].

    ``closed`` False means other is one segment (two vertices, one axis). Returns (hit, point x,
    point y, normal x, normal y, depth): the normal pushes the robot out along the shallowest axis
    (toward its side of each axis; on a tie the other shape's own face, listed last).
    """
    count = _add_normals(robot, 0, robot.shape[0], True, axes, 0)
    count = _add_normals(other, lo, hi, closed, axes, count)
    overlap, best = _shallowest(robot, other, lo, hi, axes, count, depth)
    if not overlap:
        return False, 0.0, 0.0, 0.0, 0.0, 0.0
    k = 0
    for a in range(count):
        if depth[a, 0] <= best + 1e-9 + 1e-6 * best:
            k = a
    nx, ny = axes[k, 0] * depth[k, 1], axes[k, 1] * depth[k, 1]
    px, py = _contact_point(robot, other, lo, hi, nx, ny, best)
    return True, px, py, nx, ny, best


@njit(cache=True, inline="always")
def _placed(body: FloatArray, x: float, y: float, theta: float) -> tuple[FloatArray, float]:
    """The outline body placed at pose (x, y, theta), and the reach of its vertices from its origin."""
    nv = body.shape[0]
    c, s = math.cos(theta), math.sin(theta)
    v = np.empty((nv, 2))
    reach0 = 0.0
    for k in range(nv):
        bx, by = body[k, 0], body[k, 1]
        v[k, 0], v[k, 1] = bx * c - by * s + x, bx * s + by * c + y
        reach0 = max(reach0, math.hypot(bx, by))
    return v, reach0


@njit(cache=True, inline="always")
def _spread(v: FloatArray) -> tuple[float, float, float]:
    """The centre (cx, cy) of the vertices v, and their reach from it."""
    cx, cy = _centroid(v, 0, v.shape[0])
    reach = 0.0
    for k in range(v.shape[0]):
        reach = max(reach, math.hypot(v[k, 0] - cx, v[k, 1] - cy))
    return cx, cy, reach


@njit(cache=True, inline="always")
def _nearest_edge(x: float, y: float, verts: FloatArray, lo: int, hi: int, nearest: float) -> float:
    """``nearest``, or the distance from (x, y) to the closed polygon verts[lo:hi] if it is nearer."""
    for e in range(lo, hi):
        e1 = e + 1 if e + 1 < hi else lo
        d = segment_distance(x, y, verts[e, 0], verts[e, 1], verts[e1, 0], verts[e1, 1])
        nearest = min(nearest, d)
    return nearest


@njit(cache=True, inline="always")
def _thin_near(
    x: float, y: float, cx: float, cy: float, reach: float, verts: FloatArray, lo: int, nearest: float
) -> tuple[float, bool]:
    """(``nearest`` or the distance from (x, y) to the edge verts[lo:lo+2] if nearer, whether the
    edge's closest point to the centre (cx, cy) is within reach)."""
    x0, y0, x1, y1 = verts[lo, 0], verts[lo, 1], verts[lo + 1, 0], verts[lo + 1, 1]
    nearest = min(nearest, segment_distance(x, y, x0, y0, x1, y1))
    ex, ey = x1 - x0, y1 - y0
    t = min(max(((cx - x0) * ex + (cy - y0) * ey) / (ex * ex + ey * ey), 0.0), 1.0)
    gx, gy = x0 + t * ex - cx, y0 + t * ey - cy
    return nearest, gx * gx + gy * gy < reach * reach


@njit(cache=True, inline="always")
def _insert(
    out: FloatArray, count: int, first_edge: int, closed: bool,
    px: float, py: float, nx: float, ny: float, dep: float, owner: int,
) -> int:  # fmt: skip
    """Write a contact row into out after the count rows there, edge contacts (not ``closed``)
    sorted by depth from first_edge on, deepest first (stable for equal depths); the new count."""
    a = count
    if not closed:
        while a > first_edge and out[a - 1, 4] < dep:
            for col in range(6):
                out[a, col] = out[a - 1, col]
            a -= 1
    out[a, 0], out[a, 1], out[a, 2], out[a, 3], out[a, 4], out[a, 5] = px, py, nx, ny, dep, owner
    return count + 1


@njit(cache=True, inline="always")
def _merge(out: FloatArray, first_edge: int, count: int) -> int:
    """Merge the edge contacts out[first_edge:count] of one owner whose normals are within 30 degrees
    (the first, deepest, kept); the count of rows left."""
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
    return kept


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
    v, reach0 = _placed(body, x, y, theta)
    cx, cy, reach = _spread(v)
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
            nearest = _nearest_edge(x, y, verts, lo, hi, nearest)
            inside_solid = inside_solid or _inside(x, y, verts, lo, hi)
            near = math.hypot(solid_c[k, 0] - cx, solid_c[k, 1] - cy) < reach + solid_r[k]
        else:  # a thin edge: near if its closest point to the centre is within reach
            e = k - n_solid
            verts, lo, hi, closed, owner = thin_v, 2 * e, 2 * e + 2, False, thin_owner[e]
            nearest, near = _thin_near(x, y, cx, cy, reach, verts, lo, nearest)
        if not near:
            continue
        hit, px, py, nx, ny, dep = _sat(v, verts, lo, hi, closed, axes, depth)
        if not hit:
            continue
        count = _insert(out, count, first_edge, closed, px, py, nx, ny, dep, owner)
        if closed:
            first_edge = count
    kept = _merge(out, first_edge, count)
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
