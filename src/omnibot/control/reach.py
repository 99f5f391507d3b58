"""How fast a robot's motors can carry it: free-running wheel speeds and the body speeds they allow.

A brushed DC gear motor at full PWM, unloaded by the floor, settles where its torque
eta G k (V - k G omega) / R meets its own friction tau_c + b omega (the description's motor numbers,
V the battery's nominal voltage less the driver's drop), so the wheel's free-running speed is::

    omega_free = (eta G k V / R - tau_c) / (eta G^2 k^2 / R + b)

A body twist (vx, vy, w) needs the wheel speeds J (vx, vy, w) (:mod:`omnibot.robot.kinematics`),
so the fastest a robot can translate along course c (body frame) while turning at w is where the
busiest wheel reaches its free speed. That is an upper bound: the floor's rolling resistance, the
battery's sag and the wheel-speed loop's headroom all take some of it. :func:`wheel_rows` gives
the map as rows of fractions of each wheel's free speed, what
:class:`~omnibot.control.paths.profile.MotionLimits` carries to cap the time-optimal profile.
"""

from __future__ import annotations

import math

import numpy as np

from omnibot.robot.description import RobotDescription
from omnibot.robot.kinematics import FloatArray, wheel_matrix


def free_wheel_speeds(robot: RobotDescription) -> FloatArray:
    """Each wheel's free-running speed at full PWM on the nominal battery, rad/s (see the module
    docstring); 0 for a motor whose friction its stall torque cannot overcome."""
    speeds = []
    for wheel in robot.wheels:
        m = wheel.motor
        volts = max(robot.battery.voltage - m.driver_drop, 0.0)
        drive = m.gear_efficiency * m.gear_ratio * m.torque_constant / m.resistance
        omega = (drive * volts - m.friction_static) / (
            drive * m.gear_ratio * m.torque_constant + m.friction_viscous
        )
        speeds.append(max(omega, 0.0))
    return np.array(speeds)


def wheel_rows(robot: RobotDescription) -> tuple[tuple[float, float, float], ...]:
    """The rows of J divided by each wheel's free speed: ``row . (vx, vy, w)`` is the fraction of
    that wheel's free-running speed the body twist needs (body frame, SI)."""
    J = wheel_matrix(robot)
    free = free_wheel_speeds(robot)
    rows = J / np.maximum(free, 1e-9)[:, None]
    return tuple((float(a), float(b), float(c)) for a, b, c in rows)


def course_speed_bound(robot: RobotDescription, course: float, w: float = 0.0) -> float:
    """m/s: the fastest translation along ``course`` (rad, body frame) while turning at ``w`` rad/s
    that no wheel needs more than its free-running speed for (0 when the turn alone is too fast)."""
    rows = np.array(wheel_rows(robot))
    along = rows[:, 0] * math.cos(course) + rows[:, 1] * math.sin(course)
    turn = rows[:, 2] * w
    if np.any(np.abs(turn) >= 1.0):
        return 0.0
    # wheel i needs |along_i v + turn_i| <= 1: the turn helps the wheels it runs against
    spare = 1.0 - np.sign(along) * turn
    with np.errstate(divide="ignore"):
        return float(np.min(np.where(np.abs(along) > 1e-12, spare / np.abs(along), math.inf)))


def speed_bound(robot: RobotDescription, w: float = 0.0, courses: int = 360) -> tuple[float, float]:
    """(slowest, fastest) over ``courses`` evenly spaced courses of :func:`course_speed_bound`:
    a robot reaches a speed on every course only below the first."""
    bounds = [course_speed_bound(robot, 2.0 * math.pi * k / courses, w) for k in range(courses)]
    return min(bounds), max(bounds)
