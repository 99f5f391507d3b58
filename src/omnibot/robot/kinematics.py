"""Kinematics of any omni/mecanum wheel layout (seed 003's general model), as pure functions.

Wheel i sits at p_i = (x_i, y_i) in the body frame, its contact point travels along the unit vector
u_i (``drive_angle``) for a positive wheel speed, and its rollers let it slide freely across the
direction t_i = u_i turned by the roller angle gamma_i. Only the velocity of the contact point along
t_i must be produced by the wheel, so for a body twist (vx, vy, w)::

    omega_i = t_i . (v + w x p_i) / (r_i cos gamma_i)
            = [cos(phi_i), sin(phi_i), x_i sin(phi_i) - y_i cos(phi_i)] . (vx, vy, w) / (r_i cos gamma_i)

with phi_i = drive angle + gamma. In seed 003's notation this row is
[sin(a+b+g), -cos(a+b+g), -L cos(b+g)] / (r cos g), i.e. omega = J2^-1 J1 xi.

Forward kinematics is the least-squares inverse of that map; its residual is what the wheel speeds
disagree with any rigid motion, a slip signal.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from omnibot.errors import KinematicsError

if TYPE_CHECKING:
    from omnibot.robot.description import RobotDescription

FloatArray = NDArray[np.float64]


def contact_rows(
    x: ArrayLike, y: ArrayLike, drive_angles: ArrayLike, gammas: ArrayLike
) -> tuple[FloatArray, FloatArray]:
    """Each wheel's floor contact as rows over the body twist (vx, vy, w), shape (..., 3) for
    parameter arrays of any shape: the traction row (the speed of the body at the contact along
    the rim's direction of travel, which a wheel turning at omega matches with ``r cos(gamma)
    omega``) and the roller row (across it, along the roller's axis of rolling)."""
    xa, ya = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    phi = np.asarray(drive_angles, dtype=float) + np.asarray(gammas, dtype=float)
    c, s = np.cos(phi), np.sin(phi)
    traction = np.stack((c, s, xa * s - ya * c), axis=-1)
    roller = np.stack((-s, c, xa * c + ya * s), axis=-1)
    return traction, roller


def robot_contact_rows(robot: RobotDescription) -> tuple[FloatArray, FloatArray]:
    """:func:`contact_rows` of a robot's wheels, in their order: (traction, roller), each (n, 3)."""
    wheels = robot.wheels
    return contact_rows(
        [w.position[0] for w in wheels],
        [w.position[1] for w in wheels],
        [w.drive_angle for w in wheels],
        [w.gamma for w in wheels],
    )


def wheel_rows(
    positions: ArrayLike, drive_angles: ArrayLike, gammas: ArrayLike, radii: ArrayLike
) -> FloatArray:
    """The (n, 3) matrix J with omega = J @ (vx, vy, w) for the wheel parameters given as arrays."""
    p = np.asarray(positions, dtype=float).reshape(-1, 2)
    denom = np.asarray(radii, dtype=float) * np.cos(np.asarray(gammas, dtype=float))
    if np.any(np.abs(denom) < 1e-12):
        raise KinematicsError("a wheel with gamma of +-90 degrees or zero radius cannot drive")
    traction, _ = contact_rows(p[:, 0], p[:, 1], drive_angles, gammas)
    return np.asarray(traction / denom[:, None], dtype=float)


def wheel_matrix(robot: RobotDescription) -> FloatArray:
    """Inverse-kinematics matrix J of a robot (rad/s of each wheel per unit body twist).

    Raises KinematicsError if the layout cannot produce every planar twist (rank below 3).
    """
    J = wheel_rows(
        [w.position for w in robot.wheels],
        [w.drive_angle for w in robot.wheels],
        [w.gamma for w in robot.wheels],
        [w.radius for w in robot.wheels],
    )
    check_holonomic(J, robot.name)
    return J


def check_holonomic(J: FloatArray, name: str = "this layout") -> None:
    """Raise KinematicsError unless J has rank 3 (every planar twist reachable)."""
    sv = np.linalg.svd(J, compute_uv=False)
    if sv.size < 3 or sv[2] < 1e-9 * max(sv[0], 1e-12):
        raise KinematicsError(
            f"{name} is not holonomic: its wheels constrain only {int(np.sum(sv > 1e-9 * sv[0]))} of the "
            "3 planar motions (check drive_angle/gamma: wheels pushing along the same lines cannot "
            "produce every twist)"
        )


def inverse(J: FloatArray, twist: ArrayLike) -> FloatArray:
    """Wheel angular speeds (rad/s) for a body twist (vx, vy, w) or an (m, 3) batch of twists."""
    t = np.asarray(twist, dtype=float)
    if t.shape[-1] != 3:
        raise KinematicsError(f"a twist has 3 components (vx, vy, w), got shape {t.shape}")
    return np.asarray(t @ J.T, dtype=float)


class ForwardResult(NamedTuple):
    """What :func:`forward` returns: the least-squares body twist and the per-wheel residual."""

    twist: FloatArray
    residual: FloatArray
    """Per wheel: measured minus the speed the fitted rigid motion implies (rad/s); non-zero means slip."""


def forward(J: FloatArray, wheel_speeds: ArrayLike) -> ForwardResult:
    """Least-squares body twist from wheel speeds, with the per-wheel residual as a slip signal."""
    w = np.asarray(wheel_speeds, dtype=float)
    if w.shape[-1] != J.shape[0]:
        raise KinematicsError(f"expected {J.shape[0]} wheel speeds, got {w.shape[-1]}")
    twist = w @ np.linalg.pinv(J).T
    return ForwardResult(np.asarray(twist, dtype=float), np.asarray(w - twist @ J.T, dtype=float))


def rotation(theta: float) -> FloatArray:
    """2-D rotation matrix."""
    c, s = math.cos(theta), math.sin(theta)
    return np.array([[c, -s], [s, c]])


def body_to_world(twist: ArrayLike, theta: float) -> FloatArray:
    """A body-frame twist expressed in the world frame of a robot with heading theta."""
    t = np.asarray(twist, dtype=float)
    out = t.copy()
    out[..., :2] = t[..., :2] @ rotation(theta).T
    return out


def world_to_body(twist: ArrayLike, theta: float) -> FloatArray:
    """A world-frame twist expressed in the body frame of a robot with heading theta."""
    return body_to_world(twist, -theta)


class Saturated(NamedTuple):
    """What :func:`saturate` returns: the scaled values and the common factor applied."""

    values: FloatArray
    scale: float
    """Common factor applied (1.0 when nothing exceeded the limit)."""


def saturate(values: ArrayLike, limit: float | ArrayLike) -> Saturated:
    """Scale all values by one factor so none exceeds its limit; the commanded direction is kept."""
    v = np.asarray(values, dtype=float)
    lim = np.broadcast_to(np.asarray(limit, dtype=float), v.shape)
    if np.any(lim <= 0):
        raise KinematicsError("saturation limits must be positive")
    worst = float(np.max(np.abs(v) / lim)) if v.size else 0.0
    if worst <= 1.0:
        return Saturated(v.copy(), 1.0)
    return Saturated(v / worst, 1.0 / worst)


def twist_limit_scale(J: FloatArray, twist: ArrayLike, wheel_speed_max: float) -> float:
    """Largest factor k <= 1 such that k*twist needs no wheel faster than wheel_speed_max."""
    return saturate(inverse(J, twist), wheel_speed_max).scale
