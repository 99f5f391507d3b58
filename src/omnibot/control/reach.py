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

On a floor (:func:`floor_course_speed`) the bound is where the wheels' torque-speed lines meet the
floor's load. To hold speed v along a course (no turn) the floor's forces of
:mod:`omnibot.sim.physics` at that speed must be balanced: every roller's rolling resistance
(``c N`` times the surface's multiplier, its phase-mean) and the combined rolling-and-driving drag
``b N sin(2 beta)`` on the roller, held by the wheels' traction (the least-norm forces that keep
the body on its course; they set each wheel's slip, so its speed), and at each axle that drag, the
axle friction and the traction's torque, which the motor's ``eta G k i`` must supply. The current
``i`` at the wheel's speed needs the PWM fraction ``d = (i R + k G omega) / (V_bus - V_drop)``,
the battery sagging under every motor's ``d i``. The top speed on the course is where the busiest
wheel needs full PWM (or its current limit). The same description and surface numbers the
simulator uses (one source of truth).
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from omnibot.robot.description import RobotDescription, WheelSpec
from omnibot.robot.kinematics import FloatArray, contact_rows, wheel_matrix
from omnibot.sim.surfaces import Surface, get_surface


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


FLOOR_COURSES = 72
"""Courses (evenly spaced over a turn) in a floor's speed table (:func:`floor_speed_table`)."""


def _floor_spare(
    robot: RobotDescription, floor: Surface, courses: FloatArray, speeds: FloatArray
) -> FloatArray:
    """1 less the largest PWM fraction any wheel needs to hold ``speeds`` m/s steadily along
    ``courses`` (rad, body frame; arrays of one shape (k,)) on ``floor``: positive where the
    motors can, negative where they cannot (also when a wheel would need more than its current
    limit). See the module docstring."""
    from omnibot.sim.kernels import ROLL_SPEED_EPS, WHEEL_SPEED_EPS
    from omnibot.sim.physics import static_loads

    wheels = robot.wheels

    def each(fn: Callable[[WheelSpec], float]) -> FloatArray:
        return np.array([float(fn(w)) for w in wheels])

    x, y = each(lambda w: w.position[0]), each(lambda w: w.position[1])
    gamma, radius = each(lambda w: w.gamma), each(lambda w: w.radius)
    traction, roller = contact_rows(x, y, each(lambda w: w.drive_angle), gamma)
    share = np.linalg.pinv(traction.T)  # (m, 3): the least-norm traction forces for a body force
    load = static_loads(x[None], y[None], np.array([robot.mass]), np.zeros((1, len(wheels)), bool))[0]
    twist = np.stack((np.cos(courses), np.sin(courses), np.zeros_like(courses)), axis=-1) * speeds[:, None]
    ta, na = -radius * np.cos(gamma), radius * np.sin(gamma)
    body_t, body_n = twist @ traction.T, twist @ roller.T  # (k, m)
    grip = each(lambda w: w.rollers.grip) * floor.mu * load
    res = each(lambda w: w.motor.resistance)
    ke = each(lambda w: w.motor.torque_constant * w.motor.gear_ratio)
    kt = ke * each(lambda w: w.motor.gear_efficiency)
    drop, i_max = each(lambda w: w.motor.driver_drop), each(lambda w: w.motor.current_max)
    static, viscous = each(lambda w: w.motor.friction_static), each(lambda w: w.motor.friction_viscous)
    # the phase-mean of the rollers' resistance c(phi) N on this floor, and the combined drag b N
    rolling = each(lambda w: w.rollers.rolling_resistance * (1.0 + 0.5 * w.rollers.friction_variation))
    rolling = rolling * floor.rolling_multiplier * load
    combined = each(lambda w: w.rollers.combined_drag) * load
    v_open, r_batt = robot.battery.voltage, robot.battery.internal_resistance
    relax = 1.0 / (1.0 + r_batt * float(np.sum(1.0 / res)))
    v_bus = np.full((len(courses), 1), v_open)
    omega = body_t / -ta  # rolling without slip to start
    duty = amps = np.zeros_like(omega)
    # the rollers roll at the no-slip speed: the traction's slip (mm/s) would only move the steep
    # regularised resistance of rollers that stand still, and make the fixed point below unstable
    roll = body_n + na * omega
    for _ in range(300):  # traction slip and battery sag, relaxed to their fixed point
        rim = radius * omega
        both = rim * rim + roll * roll
        sin2 = np.where(both > 1e-12, 2.0 * np.abs(rim) * np.abs(roll) / np.maximum(both, 1e-12), 0.0)
        fn = rolling * np.tanh(roll / ROLL_SPEED_EPS) + combined * sin2 * roll
        # the wheels' traction holds the body against the rollers' forces: sum ft T + fn N = 0
        ft = -(fn @ roller) @ share.T
        # each axle balances: ft ta + fn na + friction = the motor's kt i
        axle = static * np.tanh(omega / WHEEL_SPEED_EPS) + viscous * omega + combined * sin2 * radius * rim
        amps = (ft * ta + fn * na + axle) / kt
        duty = (amps * res + ke * omega) / np.maximum(v_bus - drop, 1e-9)
        sagged = v_open - r_batt * np.sum(duty * amps, axis=1, keepdims=True)
        v_bus, moved = (
            np.maximum(v_bus + relax * (sagged - v_bus), 0.0),
            float(np.max(np.abs(sagged - v_bus))),
        )
        slip = floor.slip_velocity * np.arctanh(np.clip(ft / np.maximum(grip, 1e-12), -0.999, 0.999))
        settled = 0.5 * omega + 0.5 * (slip - body_t) / ta
        if max(float(np.max(np.abs(settled - omega))), moved) < 1e-9:
            break
        omega = settled
    over_current = np.any(np.abs(amps) > i_max, axis=1)
    return np.where(over_current, -1.0, 1.0 - np.max(np.abs(duty), axis=1))


def _floor_speeds(robot: RobotDescription, surface: str | Surface, courses: FloatArray) -> FloatArray:
    """m/s: :func:`floor_course_speed` on each of ``courses`` at once (one bisection for all)."""
    floor = get_surface(surface)
    lo = np.full(courses.shape, 1e-4)
    hi = 1.5 * np.array([course_speed_bound(robot, float(c)) for c in courses])
    stalled = _floor_spare(robot, floor, courses, lo) <= 0.0
    while np.any(hi - lo > 1e-5 * hi):
        mid = 0.5 * (lo + hi)
        ahead = _floor_spare(robot, floor, courses, mid) > 0.0
        lo, hi = np.where(ahead, mid, lo), np.where(ahead, hi, mid)
    return np.where(stalled, 0.0, 0.5 * (lo + hi))


def floor_course_speed(robot: RobotDescription, course: float, surface: str | Surface) -> float:
    """m/s: the fastest steady speed along ``course`` (rad, body frame) on ``surface`` (a name or
    :class:`~omnibot.sim.surfaces.Surface`): where the busiest wheel needs full PWM against the
    floor's load (module docstring); 0 when the motors cannot move the robot on that course."""
    return float(_floor_speeds(robot, surface, np.array([float(course)]))[0])


def floor_speed_table(
    robot: RobotDescription, surface: str | Surface, courses: int = FLOOR_COURSES
) -> tuple[float, ...]:
    """:func:`floor_course_speed` on ``courses`` evenly spaced courses from 0 (body x axis), what
    :class:`~omnibot.control.paths.profile.MotionLimits` carries as its floor."""
    table = _floor_speeds(robot, surface, 2.0 * math.pi * np.arange(courses) / courses)
    return tuple(float(v) for v in table)
