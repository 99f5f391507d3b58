"""Kinematics of any omni/mecanum wheel layout in plain Python: the one source of the wheel rows, the
layout's rank check and its least-squares inverse (no numpy: ``pip install omnibot``'s core computes
them for description checks, the firmware's config and the ``kinematics`` command).

Wheel i sits at p_i = (x_i, y_i) in the body frame, its contact point travels along the unit vector
u_i (``drive_angle``) for a positive wheel speed, and its rollers let it slide freely across the
direction t_i = u_i turned by the roller angle gamma_i. With phi_i = drive angle + gamma, the wheel's
traction row over the body twist (vx, vy, w) is [cos(phi_i), sin(phi_i), x_i sin(phi_i) - y_i
cos(phi_i)] and its rad/s ``omega_i = traction_i . twist / (r_i cos gamma_i)`` (seed 003's omega =
J2^-1 J1 xi); :mod:`omnibot.robot.kinematics` holds the same over numpy arrays.

The least-squares inverse is the pseudo-inverse from a one-sided (Hestenes) Jacobi SVD of the n x 3
matrix itself: plane rotations orthogonalise its three columns, so the singular values come out with
a relative accuracy of a few rounding errors however ill-conditioned the layout (the normal
equations' 3 x 3, J^T J, would square the condition number and lose the small singular value a
rank-deficient layout is recognised by, below 1e-8 of the largest), and a rank-deficient matrix
gets the least-norm inverse of its rank, the small values cut as numpy's ``pinv`` cuts them.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING, NamedTuple

from omnibot.errors import KinematicsError

if TYPE_CHECKING:
    from omnibot.robot.description import RobotDescription

Row = tuple[float, float, float]
"""A row over the body twist (vx, vy, w)."""

Matrix = tuple[tuple[float, ...], ...]
"""A small dense matrix as a tuple of rows."""

RANK_TOLERANCE = 1e-9
"""A singular value below this share of the largest counts as zero in the rank check."""

PINV_CUTOFF = 1e-15
"""A singular value below this share of the largest is dropped from the pseudo-inverse (numpy's
``pinv`` default)."""

SWEEPS_MAX = 60
"""Jacobi sweeps before giving up on convergence (a 3-column matrix converges in 5-7)."""


class ContactRows(NamedTuple):
    """One wheel's floor contact over the body twist (vx, vy, w)."""

    traction: Row
    """The speed of the body at the contact along the rim's direction of travel, which a wheel
    turning at omega matches with ``r cos(gamma) omega``."""
    roller: Row
    """Across it, along the roller's axis of rolling."""


def contact_row(x: float, y: float, drive_angle: float, gamma: float) -> ContactRows:
    """The traction and roller rows of a wheel at (x, y) with its drive angle and roller angle."""
    phi = drive_angle + gamma
    c, s = math.cos(phi), math.sin(phi)
    return ContactRows((c, s, x * s - y * c), (-s, c, x * c + y * s))


def robot_contact_rows(robot: RobotDescription) -> tuple[tuple[Row, ...], tuple[Row, ...]]:
    """:func:`contact_row` of each of a robot's wheels, in their order: (traction rows, roller rows)."""
    each = [contact_row(w.position[0], w.position[1], w.drive_angle, w.gamma) for w in robot.wheels]
    return tuple(c.traction for c in each), tuple(c.roller for c in each)


def wheel_row(position: Sequence[float], drive_angle: float, gamma: float, radius: float) -> Row:
    """A wheel's row of J, omega = row . (vx, vy, w); KinematicsError for a wheel that cannot drive."""
    denom = radius * math.cos(gamma)
    if abs(denom) < 1e-12:
        raise KinematicsError("a wheel with gamma of +-90 degrees or zero radius cannot drive")
    a, b, c = contact_row(position[0], position[1], drive_angle, gamma).traction
    return (a / denom, b / denom, c / denom)


def wheel_matrix(robot: RobotDescription) -> tuple[Row, ...]:
    """Inverse-kinematics matrix J of a robot (rad/s of each wheel per unit body twist), checked:
    KinematicsError if the layout cannot produce every planar twist (rank below 3)."""
    J = tuple(wheel_row(w.position, w.drive_angle, w.gamma, w.radius) for w in robot.wheels)
    check_holonomic(J, robot.name)
    return J


def check_holonomic(J: Sequence[Sequence[float]], name: str = "this layout") -> None:
    """Raise KinematicsError unless J has rank 3 (every planar twist reachable)."""
    sv = singular_values(J)
    if len(J) < 3 or sv[2] < RANK_TOLERANCE * max(sv[0], 1e-12):
        rank = sum(v > RANK_TOLERANCE * sv[0] for v in sv[: len(J)])
        raise KinematicsError(
            f"{name} is not holonomic: its wheels constrain only {rank} of the "
            "3 planar motions (check drive_angle/gamma: wheels pushing along the same lines cannot "
            "produce every twist)"
        )


class Svd(NamedTuple):
    """A thin SVD, A = U diag(s) V^T, singular values in descending order."""

    u: Matrix
    """(n, k) orthonormal columns (a zero column for a zero singular value)."""
    s: tuple[float, ...]
    v: Matrix
    """(k, k) orthogonal."""


def svd(A: Sequence[Sequence[float]]) -> Svd:
    """The thin SVD of an (n, k) matrix by one-sided Jacobi rotations of its columns (module
    docstring); k is small (3 here), n any."""
    k = len(A[0]) if A else 0
    cols = [[float(row[j]) for row in A] for j in range(k)]
    vcols = [[1.0 if i == j else 0.0 for i in range(k)] for j in range(k)]
    for _ in range(SWEEPS_MAX):
        rotated = False
        for p in range(k - 1):
            for q in range(p + 1, k):
                rotated |= _rotate(cols, vcols, p, q)
        if not rotated:
            break
    norms = [math.sqrt(math.fsum(x * x for x in c)) for c in cols]
    order = sorted(range(k), key=lambda j: -norms[j])
    u = [[x / norms[j] if norms[j] > 0.0 else 0.0 for x in cols[j]] for j in order]
    return Svd(transpose(u), tuple(norms[j] for j in order), transpose([vcols[j] for j in order]))


def _rotate(cols: list[list[float]], vcols: list[list[float]], p: int, q: int) -> bool:
    """One Jacobi rotation making columns p and q orthogonal (and the same to V's); False when they
    already are, to rounding."""
    a, b = cols[p], cols[q]
    alpha = math.fsum(x * x for x in a)
    beta = math.fsum(x * x for x in b)
    gamma = math.fsum(x * y for x, y in zip(a, b, strict=True))
    if gamma == 0.0 or abs(gamma) <= 1e-15 * math.sqrt(alpha * beta):
        return False
    zeta = (beta - alpha) / (2.0 * gamma)
    t = math.copysign(1.0, zeta) / (abs(zeta) + math.hypot(1.0, zeta))
    c = 1.0 / math.hypot(1.0, t)
    s = c * t
    for pair in ((a, b), (vcols[p], vcols[q])):
        x, y = pair
        for i, (xi, yi) in enumerate(zip(x, y, strict=True)):
            x[i], y[i] = c * xi - s * yi, s * xi + c * yi
    return True


def singular_values(A: Sequence[Sequence[float]]) -> tuple[float, ...]:
    """The singular values of A, largest first (as many as A has columns)."""
    return svd(A).s


def pseudo_inverse(A: Sequence[Sequence[float]], cutoff: float = PINV_CUTOFF) -> Matrix:
    """The (k, n) Moore-Penrose pseudo-inverse of an (n, k) matrix: the least-squares inverse,
    least-norm where A is rank-deficient (singular values below ``cutoff`` of the largest dropped)."""
    u, s, v = svd(A)
    keep = [j for j, value in enumerate(s) if value > cutoff * s[0]] if s and s[0] > 0.0 else []
    return tuple(
        tuple(math.fsum(v[i][j] / s[j] * u[r][j] for j in keep) for r in range(len(u))) for i in range(len(v))
    )


def transpose(A: Sequence[Sequence[float]]) -> Matrix:
    """The transpose of A."""
    return tuple(zip(*A, strict=True)) if A else ()


def apply(A: Sequence[Sequence[float]], x: Sequence[float]) -> tuple[float, ...]:
    """The matrix-vector product A x."""
    return tuple(sum(a * b for a, b in zip(row, x, strict=True)) for row in A)


class Forward(NamedTuple):
    """What :func:`forward` returns: the least-squares body twist and the per-wheel residual."""

    twist: tuple[float, ...]
    residual: tuple[float, ...]
    """Per wheel: measured minus the speed the fitted rigid motion implies (rad/s); non-zero means slip."""


def forward(J: Sequence[Sequence[float]], wheel_speeds: Sequence[float]) -> Forward:
    """Least-squares body twist from wheel speeds, with the per-wheel residual as a slip signal."""
    if len(wheel_speeds) != len(J):
        raise KinematicsError(f"expected {len(J)} wheel speeds, got {len(wheel_speeds)}")
    twist = apply(pseudo_inverse(J), wheel_speeds)
    return Forward(twist, tuple(w - v for w, v in zip(wheel_speeds, apply(J, twist), strict=True)))
