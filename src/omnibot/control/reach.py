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
:class:`~omnibot.control.paths.limits.MotionLimits` carries to cap the time-optimal profile.

On a floor (:func:`floor_course_speed`) the bound is where the wheels' torque-speed lines meet the
floor's load. To hold speed v along a course (no turn) the floor's forces of the simulator's
physics (:mod:`omnibot.sim.physics`, on the floor model of :mod:`omnibot.floor`) at that speed
must be balanced: every roller's rolling resistance
(``c N`` times the surface's multiplier, its phase-mean) and the combined rolling-and-driving drag
``b N sin(2 beta)`` on the roller, held by the wheels' traction (the least-norm forces that keep
the body on its course; they set each wheel's slip, so its speed), and at each axle that drag, the
axle friction and the traction's torque, which the motor's ``eta G k i`` must supply. The current
``i`` at the wheel's speed needs the PWM fraction ``d = (i R + k G omega) / (V_bus - V_drop)``,
the battery sagging under every motor's ``d i``. The top speed on the course is where the busiest
wheel needs full PWM (or its current limit). The same description and surface numbers the
simulator uses (one source of truth).

:func:`floor_reach` does the same for any body twist (vx, vy, w): each wheel's speed is its
translation part plus its rotation part, so a turn takes reach from the translation (or, on a
wheel it runs against, gives some): a table over the body course and the turn's share of the
twist, :class:`FloorReach`. :func:`floor_grip` gives what the wheels' grip (mu N) leaves for
accelerating beside the floor's drag, as a fraction of the robot's accelerations at each speed:
past it a wheel's creep grows far faster than its force (the simulator's slip is
v_s artanh(F / mu N)) and its encoder over-reads.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from omnibot.floor import GRAVITY, ROLL_SPEED_EPS, WHEEL_SPEED_EPS, Surface, get_surface, static_loads
from omnibot.robot import RobotDescription, WheelSpec
from omnibot.robot.kinematics import FloatArray, contact_rows, pseudo_inverse, wheel_matrix


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
    robot: RobotDescription, floor: Surface, twist: FloatArray, wrench: FloatArray | None = None
) -> FloatArray:
    """1 less the largest PWM fraction any wheel needs to hold each body ``twist`` (k, 3) of
    (vx, vy, w) on ``floor`` while giving the body ``wrench`` (k, 3: force x, y in N and torque
    in N m, body frame; None: steady, no wrench): positive where the motors can, negative where
    they cannot (also when a wheel would need more than its current limit). See the module
    docstring."""
    duty, amps, _ = _floor_load(robot, floor, twist, wrench)
    i_max = np.array([w.motor.current_max for w in robot.wheels])
    over_current = np.any(np.abs(amps) > i_max, axis=1)
    return np.where(over_current, -1.0, 1.0 - np.max(np.abs(duty), axis=1))


def _floor_load(
    robot: RobotDescription, floor: Surface, twist: FloatArray, wrench: FloatArray | None = None
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Each wheel's PWM fraction, current (A) and traction force as a fraction of its grip, each
    (k, m), holding the body ``twist`` (k, 3) while giving it ``wrench`` (:func:`_floor_spare`)."""
    wheels = robot.wheels

    def each(fn: Callable[[WheelSpec], float]) -> FloatArray:
        return np.array([float(fn(w)) for w in wheels])

    x, y = each(lambda w: w.position[0]), each(lambda w: w.position[1])
    gamma, radius = each(lambda w: w.gamma), each(lambda w: w.radius)
    traction, roller = contact_rows(x, y, each(lambda w: w.drive_angle), gamma)
    share = pseudo_inverse(traction.T)  # (m, 3): the least-norm traction forces for a body force
    load = static_loads(x[None], y[None], np.array([robot.mass]), np.zeros((1, len(wheels)), bool))[0]
    ta, na = -radius * np.cos(gamma), radius * np.sin(gamma)
    body_t, body_n = twist @ traction.T, twist @ roller.T  # (k, m)
    grip = each(lambda w: w.rollers.grip) * floor.mu * load
    res = each(lambda w: w.motor.resistance)
    ke = each(lambda w: w.motor.torque_constant * w.motor.gear_ratio)
    kt = ke * each(lambda w: w.motor.gear_efficiency)
    drop = each(lambda w: w.motor.driver_drop)
    static, viscous = each(lambda w: w.motor.friction_static), each(lambda w: w.motor.friction_viscous)
    # the phase-mean of the rollers' resistance c(phi) N on this floor, and the combined drag b N
    rolling = each(lambda w: w.rollers.rolling_resistance * (1.0 + 0.5 * w.rollers.friction_variation))
    rolling = rolling * floor.rolling_multiplier * load
    combined = each(lambda w: w.rollers.combined_drag) * load
    v_open, r_batt = robot.battery.voltage, robot.battery.internal_resistance
    relax = 1.0 / (1.0 + r_batt * float(np.sum(1.0 / res)))
    v_bus = np.full((len(twist), 1), v_open)
    omega = body_t / -ta  # rolling without slip to start
    duty = amps = ft = np.zeros_like(omega)
    # the rollers roll at the no-slip speed: the traction's slip (mm/s) would only move the steep
    # regularised resistance of rollers that stand still, and make the fixed point below unstable
    roll = body_n + na * omega
    push = np.zeros_like(twist) if wrench is None else wrench
    for _ in range(300):  # traction slip and battery sag, relaxed to their fixed point
        rim = radius * omega
        both = rim * rim + roll * roll
        sin2 = np.where(both > 1e-12, 2.0 * np.abs(rim) * np.abs(roll) / np.maximum(both, 1e-12), 0.0)
        fn = rolling * np.tanh(roll / ROLL_SPEED_EPS) + combined * sin2 * roll
        # ft and fn are the forces the contacts put on the floor (the body feels them reversed):
        # the wheels' traction holds the body against the rollers' and gives it the wrench
        ft = -(push + fn @ roller) @ share.T
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
    return duty, amps, ft / np.maximum(grip, 1e-12)


def _floor_reach(robot: RobotDescription, surface: str | Surface, directions: FloatArray) -> FloatArray:
    """The largest multiple of each body twist in ``directions`` (k, 3) that the motors can hold
    steadily on ``surface`` (module docstring; one bisection for all); 0 where they cannot move it."""
    floor = get_surface(surface)
    rows = np.array(wheel_rows(robot))
    lo = np.full(len(directions), 1e-4)
    hi = 1.5 / np.maximum(np.max(np.abs(directions @ rows.T), axis=1), 1e-9)  # the free-speed bound
    stalled = _floor_spare(robot, floor, lo[:, None] * directions) <= 0.0
    while np.any(hi - lo > 1e-5 * hi):
        mid = 0.5 * (lo + hi)
        ahead = _floor_spare(robot, floor, mid[:, None] * directions) > 0.0
        lo, hi = np.where(ahead, mid, lo), np.where(ahead, hi, mid)
    return np.where(stalled, 0.0, 0.5 * (lo + hi))


def _floor_speeds(robot: RobotDescription, surface: str | Surface, courses: FloatArray) -> FloatArray:
    """m/s: :func:`floor_course_speed` on each of ``courses`` at once."""
    return _floor_reach(robot, surface, np.stack((np.cos(courses), np.sin(courses), 0.0 * courses), axis=-1))


def floor_course_speed(robot: RobotDescription, course: float, surface: str | Surface) -> float:
    """m/s: the fastest steady speed along ``course`` (rad, body frame) on ``surface`` (a name or
    :class:`~omnibot.floor.surfaces.Surface`): where the busiest wheel needs full PWM against the
    floor's load (module docstring); 0 when the motors cannot move the robot on that course."""
    return float(_floor_speeds(robot, surface, np.array([float(course)]))[0])


def floor_speed_table(
    robot: RobotDescription, surface: str | Surface, courses: int = FLOOR_COURSES
) -> tuple[float, ...]:
    """:func:`floor_course_speed` on ``courses`` evenly spaced courses from 0 (body x axis): the
    translation row of :func:`floor_reach`."""
    table = _floor_speeds(robot, surface, 2.0 * math.pi * np.arange(courses) / courses)
    return tuple(float(v) for v in table)


TURN_SHARES = 37
"""Turn shares (evenly spaced from a turn to the right to one to the left, 5 degrees apart) in a
floor's reach table (:func:`floor_reach`)."""


def turn_radius(robot: RobotDescription) -> float:
    """m: the wheels' mean distance from the centre, the length that makes a turn rate a speed
    (R w is about the rim speed a turn asks of a wheel) in :class:`FloorReach`."""
    return float(np.mean([math.hypot(*w.position) for w in robot.wheels]))


@dataclass(frozen=True)
class FloorReach:
    """How far each body twist can go on a floor: the motors' steady reach (:func:`floor_reach`).

    A twist (vx, vy, w) has a course c = atan2(vy, vx) and a turn share phi = atan2(R w, v) (v its
    speed, R :attr:`radius`); ``table[j][k]`` is the largest hypot(v, R w) the motors hold on turn
    share j (evenly from -90 to 90 degrees) and course k (evenly over a turn from 0, the body's x
    axis). Row ``len(table) // 2`` (share 0) is translation alone (:func:`floor_speed_table`), the
    last and first rows turning in place. In between, the table is interpolated bilinearly.
    """

    radius: float
    table: tuple[tuple[float, ...], ...]

    def __post_init__(self) -> None:
        widths = {len(row) for row in self.table}
        if not self.radius > 0 or len(self.table) < 3 or len(self.table) % 2 == 0:
            raise ValueError("a floor reach needs a positive radius and an odd number (>= 3) of turn shares")
        if len(widths) != 1 or min(widths) < 2 or not all(v > 0 for row in self.table for v in row):
            raise ValueError("a floor reach needs at least two courses per share, each with a positive reach")

    @property
    def courses(self) -> tuple[float, ...]:
        """m/s: the top speed on each course with no turn (the share-0 row)."""
        return self.table[len(self.table) // 2]

    def multiple(self, twist: FloatArray) -> FloatArray:
        """The largest factor each body twist of ``twist`` (k, 3) may be multiplied by within the
        reach (inf for a zero twist)."""
        grid = np.array(self.table)
        shares, courses = grid.shape
        grid = np.concatenate((grid, grid[:, :1]), axis=1)  # the course wraps round
        speed = np.hypot(twist[:, 0], twist[:, 1])
        turn = self.radius * twist[:, 2]
        size = np.hypot(speed, turn)
        share = (np.arctan2(turn, speed) / math.pi + 0.5) * (shares - 1)  # 0 .. shares - 1
        course = np.mod(np.arctan2(twist[:, 1], twist[:, 0]), 2.0 * math.pi) * courses / (2.0 * math.pi)
        j = np.clip(np.floor(share).astype(int), 0, shares - 2)
        k = np.minimum(np.floor(course).astype(int), courses - 1)
        fj, fk = share - j, course - k
        reach = (1.0 - fj) * ((1.0 - fk) * grid[j, k] + fk * grid[j, k + 1]) + fj * (
            (1.0 - fk) * grid[j + 1, k] + fk * grid[j + 1, k + 1]
        )
        with np.errstate(divide="ignore"):
            return np.where(size > 1e-12, reach / np.maximum(size, 1e-12), math.inf)

    def at(self, course: float, w: float) -> float:
        """m/s: the fastest translation along ``course`` (rad, body frame) while turning at ``w``
        rad/s (0 when the turn alone is beyond reach), from the table."""
        direction = np.array([[math.cos(course), math.sin(course), 0.0]])
        lo, hi = 0.0, max(max(row) for row in self.table)  # the reach is at least the speed
        if self.multiple(np.array([[0.0, 0.0, w]]))[0] < 1.0:
            return 0.0
        for _ in range(40):  # the speed at which (v, w) reaches the table's edge
            mid = 0.5 * (lo + hi)
            inside = self.multiple(np.array([[mid * direction[0, 0], mid * direction[0, 1], w]]))[0] >= 1.0
            lo, hi = (mid, hi) if inside else (lo, mid)
        return lo


def floor_reach(
    robot: RobotDescription, surface: str | Surface, courses: int = FLOOR_COURSES, shares: int = TURN_SHARES
) -> FloorReach:
    """The motors' steady reach on ``surface`` for every body twist (:class:`FloorReach`): the
    translation of :func:`floor_course_speed` and a turn together, each wheel's speed the sum of
    its translation and rotation parts, the busiest at full PWM against the floor's load (module
    docstring). What :class:`~omnibot.control.paths.limits.MotionLimits` carries as its floor."""
    radius = turn_radius(robot)
    phi = np.linspace(-0.5 * math.pi, 0.5 * math.pi, shares)[:, None]
    course = 2.0 * math.pi * np.arange(courses)[None, :] / courses
    directions = np.stack(
        np.broadcast_arrays(np.cos(phi) * np.cos(course), np.cos(phi) * np.sin(course), np.sin(phi) / radius),
        axis=-1,
    ).reshape(-1, 3)
    table = _floor_reach(robot, surface, directions).reshape(shares, courses)
    return FloorReach(radius, tuple(tuple(float(v) for v in row) for row in table))


COURSE_DRIFT = 0.02
"""m per m of path: the sideways drift the wheels' creep may cost the odometry, the budget of
:func:`floor_course_rate` (set on omni4 and mecanum4 figure eights on carpet, 2026-12-06: their
odometry drifted sideways by 0.018-0.022 m/s per m/s^2 of lateral acceleration, and 1 cm RMS held
where the course turned at up to 0.8 rad/s)."""


def floor_course_rate(surface: str | Surface) -> float:
    """rad/s: the fastest the direction of travel may turn on ``surface`` for the wheels' sideways
    creep to drift the odometry by at most :data:`COURSE_DRIFT` per metre.

    In a turn the wheels carry the lateral acceleration a = v^2 kappa; they creep sideways at about
    v_s a / (mu g) times the floor's roller drag (its ``rolling_multiplier``: the rollers that
    should roll sideways drag), which the encoders do not see. Per metre that is v_s m_r v kappa /
    (mu g): capping the course's turn rate v kappa caps the drift (carpet 1.6 rad/s, wood 5.9).
    """
    floor = get_surface(surface) if isinstance(surface, str) else surface
    creep = floor.slip_velocity * floor.rolling_multiplier / (floor.mu * GRAVITY)
    return COURSE_DRIFT / creep


GRIP_SPEEDS = 12
"""Speeds (evenly from standstill to the top speed) in a floor's grip table (:func:`floor_grip`)."""
GRIP_COURSES = 36
"""Courses (evenly over a turn) :func:`floor_grip` takes the worst of."""
GRIP_LEAST = 0.05
"""The least fraction of its accelerations :func:`floor_grip` leaves a robot (where the floor's drag
alone takes the grip, beyond the floor's reach, the profile must still move)."""


def floor_grip(
    robot: RobotDescription, surface: str | Surface, top: float, speeds: int = GRIP_SPEEDS
) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """The accelerations the wheels' grip leaves beside the floor's drag: at each of ``speeds``
    speeds evenly from 0 to ``top`` m/s (at 0: a creep, the rollers' resistance already on), the
    largest fraction (at most 1) of the robot's limits,
    accelerating at ``acceleration_max`` along the course while the turn accelerates at half
    ``angular_acceleration_max`` (what :func:`~omnibot.control.paths.profile.time_optimal_profile`
    asks at once), for which no wheel's traction (the body's force and torque shared least-norm
    over the wheels, with the rollers' drag at that speed) exceeds its grip, on the worst course
    and either turn. Returns (speeds, fractions)."""
    floor = get_surface(surface)
    limits = robot.limits
    v = np.linspace(0.0, top, speeds)
    # the rollers' resistance is there as soon as the robot creeps: at standstill, that of a creep
    moving = np.concatenate(([min(4.0 * ROLL_SPEED_EPS, 0.5 * v[1])], v[1:]))
    c = 2.0 * math.pi * np.arange(GRIP_COURSES) / GRIP_COURSES
    vv, cc, ss = (a.ravel() for a in np.meshgrid(moving, c, (1.0, -1.0), indexing="ij"))
    twist = np.stack((vv * np.cos(cc), vv * np.sin(cc), 0.0 * vv), axis=-1)
    push = np.stack(
        (
            robot.mass * limits.acceleration_max * np.cos(cc),
            robot.mass * limits.acceleration_max * np.sin(cc),
            ss * 0.5 * robot.yaw_inertia * limits.angular_acceleration_max,
        ),
        axis=-1,
    )

    def held(k: FloatArray) -> FloatArray:
        grip = _floor_load(robot, floor, twist, k[:, None] * push)[2]
        held_all: FloatArray = np.max(np.abs(grip), axis=1) <= 1.0
        return held_all

    lo, hi = np.zeros(len(vv)), np.ones(len(vv))
    full = held(hi)
    for _ in range(14):
        mid = 0.5 * (lo + hi)
        ok = held(mid)
        lo, hi = np.where(ok, mid, lo), np.where(ok, hi, mid)
    k = np.where(full, 1.0, lo).reshape(speeds, -1).min(axis=1)
    return tuple(float(x) for x in v), tuple(float(max(x, GRIP_LEAST)) for x in k)
