"""Kinematics of any omni/mecanum wheel layout (seed 003's general model) over numpy arrays: batches of
twists and wheel speeds, contact rows of many wheels or robots at once.

The model, its rank check and its least-squares inverse are :mod:`omnibot.robot.rows`' (plain
Python, the core install's); this module gives the same numbers as arrays (seed 003's omega = J2^-1
J1 xi row by row). Forward kinematics is the least-squares inverse of the wheel map; its residual is
what the wheel speeds disagree with any rigid motion, a slip signal.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from omnibot.errors import KinematicsError
from omnibot.robot import rows

if TYPE_CHECKING:
    from omnibot.robot.description import RobotDescription

FloatArray = NDArray[np.float64]


def _contact_numbers(x: float, y: float, drive_angle: float, gamma: float) -> tuple[float, ...]:
    traction, roller = rows.contact_row(x, y, drive_angle, gamma)
    return (*traction, *roller)


_CONTACT = np.vectorize(_contact_numbers, otypes=[float] * 6)


def contact_rows(
    x: ArrayLike, y: ArrayLike, drive_angles: ArrayLike, gammas: ArrayLike
) -> tuple[FloatArray, FloatArray]:
    """:func:`omnibot.robot.rows.contact_row` over parameter arrays of any (broadcast) shape: the
    traction and roller rows over the body twist (vx, vy, w), each of shape (..., 3)."""
    numbers = _CONTACT(x, y, drive_angles, gammas)
    return np.stack(numbers[:3], axis=-1), np.stack(numbers[3:], axis=-1)


def robot_contact_rows(robot: RobotDescription) -> tuple[FloatArray, FloatArray]:
    """:func:`contact_rows` of a robot's wheels, in their order: (traction, roller), each (n, 3)."""
    traction, roller = rows.robot_contact_rows(robot)
    return np.array(traction, dtype=float), np.array(roller, dtype=float)


def wheel_rows(
    positions: ArrayLike, drive_angles: ArrayLike, gammas: ArrayLike, radii: ArrayLike
) -> FloatArray:
    """The (n, 3) matrix J with omega = J @ (vx, vy, w) for the wheel parameters given as arrays."""
    p = np.asarray(positions, dtype=float).reshape(-1, 2)
    drive, gamma, radius = (
        np.broadcast_to(np.asarray(a, dtype=float), (len(p),)) for a in (drive_angles, gammas, radii)
    )
    return np.array(
        [
            rows.wheel_row(*wheel)
            for wheel in zip(p.tolist(), drive.tolist(), gamma.tolist(), radius.tolist(), strict=True)
        ],
        dtype=float,
    ).reshape(-1, 3)


def wheel_matrix(robot: RobotDescription) -> FloatArray:
    """Inverse-kinematics matrix J of a robot (rad/s of each wheel per unit body twist): its
    :attr:`~omnibot.robot.RobotDescription.inverse_rows` as an array.

    Raises KinematicsError if the layout cannot produce every planar twist (rank below 3).
    """
    return np.array(robot.inverse_rows, dtype=float)


def forward_matrix(robot: RobotDescription) -> FloatArray:
    """The least-squares inverse of :func:`wheel_matrix`, (3, n): body twist per wheel speeds (its
    :attr:`~omnibot.robot.RobotDescription.forward_rows` as an array)."""
    return np.array(robot.forward_rows, dtype=float)


def pseudo_inverse(A: ArrayLike) -> FloatArray:
    """:func:`omnibot.robot.rows.pseudo_inverse` of a 2-D array."""
    return np.array(rows.pseudo_inverse(_plain(A)), dtype=float).reshape(np.shape(A)[::-1])


def _plain(A: ArrayLike) -> list[list[float]]:
    plain: list[list[float]] = np.asarray(A, dtype=float).tolist()
    return plain


def check_holonomic(J: ArrayLike, name: str = "this layout") -> None:
    """Raise KinematicsError unless J has rank 3 (:func:`omnibot.robot.rows.check_holonomic`)."""
    rows.check_holonomic(_plain(J), name)


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
    """Least-squares body twist from wheel speeds (one set or an (m, n) batch), with the per-wheel
    residual as a slip signal."""
    w = np.asarray(wheel_speeds, dtype=float)
    if w.shape[-1] != J.shape[0]:
        raise KinematicsError(f"expected {J.shape[0]} wheel speeds, got {w.shape[-1]}")
    twist = w @ pseudo_inverse(J).T
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
