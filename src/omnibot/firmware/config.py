"""Host side (CPython): the firmware's plain config dict from a robot description, and board files.

The firmware reads only plain literals (MicroPython has no pydantic or numpy), so everything derived
from the description is computed here: the rim-speed matrix (inverse kinematics times wheel radius),
the idle axes for folding the course, calibration tables as lists, limits in protocol units.

::

    python -m omnibot.firmware.config omni4 board/          # stage files for mpremote
    python -m omnibot.firmware.config omni4 --print         # print robot_config.py

Keys of the config dict (all plain ints, floats, strings, lists, dicts):

==========================  =======================================================================
name, motors                robot name (HELLO) and motor count
pwm_max, power_min          PWM full scale; dead band (largest ``motor.deadband`` unless given)
pwm_dither                  optional (absent: off): True dithers an open-loop motion's fractional powers over
                            control periods (power.py); off, each is rounded once, as the UNO does
vel_dead_band               True: an open-loop VEL sets a wheel below the K_l tables' dead band to 0
                            (WARN 12; the UNO firmware always does)
radius                      wheel radii, m
J                           inverse kinematics, rad/s of each wheel per (vx, vy, w) in m/s, rad/s
rim                         J times the wheel radius: rim speed (m/s) per unit twist
idle_axes                   directions (deg, 0..180) of travel along which some wheel stands still
                            (the roller drag's)
kl_axes                     the axes (deg) K_l's and the reach's courses fold from: the idle axes on
                            omni wheels, [0] on a mecanum base (courses 0..90; robot/courses.py)
k                           calibration K, PWM counts per m/s of rim speed
kl_courses, kl_tables       K_l: courses (deg) and one [powers, factors] table per course
kt, kr                      K_t and K_r as [powers, factors]
motor_offset, motor_gain    motor map: each motor's dead-band offset (counts) and [powers, gains]
motor_speed                 motor map: each motor's speed term, PWM counts per m/s of its rim speed
roller_cos, roller_sin      roller drag coefficients of each wheel, PWM counts (0: none)
roller_coast                [speeds cm/s, s]: how long the drag outlasts a MOVE (its coast)
reach                       [folded courses deg, speeds cm/s]: the calibrated reach ([[0], [0]]: none)
roller_dir                  each wheel's rollers' rolling direction in the body frame, [x, y]
roller_pitch                encoder counts per roller pitch of each wheel (0: no encoder)
distance_max_cm             exclusive bound of abs(L) (MOVE)
speed_min_cms/speed_max_cms inclusive bounds of abs(V)
curvature_max               exclusive bound of abs(C), 1/(1000 cm)
rate_max_dps                exclusive bound of abs(F) and abs(W), deg/s
queue_capacity, line_max    command queue slots, longest command
baud, loop_hz               UART speed; nominal main-loop rate (informative)
mode                        MODE bits at reset (bit 1 when controller.wheel_speed_control)
encoder_cpr                 counts per wheel revolution of each motor's encoder, 0 = none
travel                      [x row, y row]: body travel (m, body frame) per encoder count of each wheel,
                            the least-squares forward kinematics (0 for a wheel without an encoder)
turn                        body rotation (rad) per encoder count of each wheel, the forward
                            kinematics' third row (a closed-loop ROTATE lands on it; landing.py)
slip                        the floor's wheel creep [roll m/s, combined, scale] (estimation/slip.py,
                            from ``omnibot calibrate``'s slip runs; CAL table 9); [0, 0, 1]: none
creep_roll, creep_rim       per wheel: its roller row's rolling speed and its rim speed per body twist
creep_mix                   (n, n): wheel k's over-turn (rad/s) per m/s of roller row j's creep term
                            (a landing's travel, less the creep; landing.py)
land_accel                  [m/s^2, rad/s^2]: the acceleration a closed-loop MOVE (ROTATE) ramps up and
                            down at to land on its distance (angle): a share of the description's limits
progress_tolerance          a MOVE whose encoders measure it short of its distance by more than this
                            share, once the wheels stand still, gets WARN 17 (0: no check; progress.py)
speed_kp, speed_ki          wheel-speed PI gains, PWM counts per rad/s (and per rad)
speed_band                  rad/s (where kp gives 5 % of full power): a target jump larger than it is
                            a step, after which the integral grows at 1 / (1 + (err / band)^2)
speed_ki_steady             the integral's gain once a wheel's target has held still 5 control periods
                            (the correction stays speed_ki times the integral; speedctl.py)
body_ff                     per wheel [x, y, w]: PWM counts per m/s^2 of the body's acceleration along
                            its x and y axes and per rad/s^2 of its angular acceleration (the wheel's
                            least-norm share of the force and torque; a VEL's planned acceleration,
                            fed forward by the closed loop)
wheel_ff                    per wheel: PWM counts per rad/s^2 of the wheel's own angular acceleration
                            (its and its rotor's inertia)
control_period_ms           wheel-speed control period
tracking, gyro              number of tracking wheels; True when there is a gyro
sonar_period_min_ms         one entry per sonar: its shortest period (>= 60 ms)
sonar_axes                  one entry per sonar: [axis deg, half cone deg, footprint lead cm, half width cm]
stop_decel_cms2             deceleration the robot surely reaches when stopped, cm/s^2 (sonar stop)
uncovered_speed_cms         fastest travel where no armed sonar looks, cm/s
accel_max_cms2              the robot's acceleration limit, cm/s^2: the closed loop slews a VEL without a
                            planned acceleration at it (and brakes to rest at it)
angular_accel_max_dps2      the same for the turn rate, deg/s^2
battery_mv                  [warn, limit, stop, hysteresis], mV: the battery's thresholds (battery.py)
battery_filter_ms           time constant of the battery reading's low-pass filter
battery_delay_ms            how long the filtered reading stays below a threshold before its level
battery_limit_pct           share of full power the motors get below the limit threshold, %
pins                        board pin map for MachineHAL (see hal.py)
==========================  =======================================================================
"""

from __future__ import annotations

import argparse
import math
import shutil
import sys
from pathlib import Path
from typing import Any

from omnibot.errors import ConfigError, OmnibotError
from omnibot.estimation import SlipParameters, creep_rows
from omnibot.firmware import mpu6050
from omnibot.robot import (
    PiecewiseLinear,
    RobotDescription,
    SonarSpec,
    course_axes,
    courses,
    load_robot,
    rows,
)

PACKAGE_DIR = Path(__file__).resolve().parent
SRC_DIR = PACKAGE_DIR.parent.parent
BOARD_MODULES = (
    "battery",
    "binlink",
    "calibration",
    "controller",
    "controller_commands",
    "controller_input",
    "controller_replies",
    "controller_state",
    "hal",
    "landing",
    "limits",
    "motion",
    "motion_brake",
    "motion_commands",
    "motion_drive",
    "motion_landing",
    "motion_state",
    "mpu6050",
    "parser",
    "power",
    "progress",
    "queue",
    "safety",
    "sonar",
    "speedctl",
    "telemetry",
    "watchdog",
)
PROTOCOL_MODULES = ("codes", "crc", "frame", "arq", "linecheck")


def gyro_pins(robot: RobotDescription) -> list[int] | None:
    """The pin map's ``gyro`` entry (hal.py) from the description's MPU6050 wiring: ``[i2c_id, scl,
    sda, address, freq, fs_sel, dlpf_cfg]``; None without a gyro or for another model (no driver)."""
    g = robot.gyro
    if g is None or g.model.upper() != "MPU6050":
        return None
    range_dps = math.degrees(g.range)
    try:
        fs_sel = mpu6050.fs_sel_for(range_dps)
    except ValueError:
        raise ConfigError(
            f"{g.range} rad/s ({range_dps:.0f} deg/s) is beyond an MPU6050's 2000 deg/s",
            key="gyro.range",
        ) from None
    lsb = mpu6050.LSB_PER_DPS_X10[fs_sel] / 10.0  # counts per deg/s
    if g.resolution > 0 and abs(math.radians(1.0 / lsb) / g.resolution - 1.0) > 0.02:
        raise ConfigError(
            f"{g.resolution} rad/s per LSB does not match the MPU6050's "
            f"+-{mpu6050.FULL_SCALE_DPS[fs_sel]} deg/s range that gyro.range picks "
            f"({math.radians(1.0 / lsb):.4g} rad/s per LSB, {lsb:g} LSB per deg/s)",
            key="gyro.resolution",
        )
    return [
        g.i2c_bus,
        g.scl_pin,
        g.sda_pin,
        g.i2c_address,
        g.i2c_freq,
        fs_sel,
        mpu6050.dlpf_cfg_for(g.bandwidth_hz),
    ]


def default_pins(robot: RobotDescription) -> dict[str, Any]:
    """An example pin map for a Raspberry Pi Pico (RP2040); edit it for your wiring. The gyro's I2C
    pins come from the description; where they take the UART's (GP0, GP1: the defaults do), the
    protocol runs on USB (``"uart": None``). A pin used twice is a ConfigError naming the gyro's key."""
    n = robot.n_wheels
    gyro = gyro_pins(robot)
    uart: list[int] | None = [0, 0, 1]
    if gyro is not None and {gyro[1], gyro[2]} & {0, 1}:
        uart = None
    pins: dict[str, Any] = {
        "uart": uart,
        "pwm_freq": 1000,
        "motors": [[2 + 3 * i, 3 + 3 * i, 4 + 3 * i] for i in range(n)],
        "encoders": [[14 + 2 * i, 15 + 2 * i] for i in range(n)] if robot.encoders.motors else [],
        "tracking": [],
        "sonars": [[22, 26]][: len(robot.sonars)],
        "battery": [28, round(3300.0 * 3 / 65535, 6)],
        "gyro": gyro,
    }
    if gyro is not None:
        used = _pins_used(pins, but="gyro")
        for key, pin in (("gyro.scl_pin", gyro[1]), ("gyro.sda_pin", gyro[2])):
            if pin in used:
                raise ConfigError(
                    f"pin {pin} is the board's {used[pin]} pin already (free pins: "
                    f"{', '.join(str(p) for p in range(29) if p not in used and p not in (23, 24, 25))})",
                    key=key,
                )
        if gyro[1] == gyro[2]:
            raise ConfigError(f"SCL and SDA are both pin {gyro[1]}", key="gyro.scl_pin")
    return pins


def _pins_used(pins: dict[str, Any], but: str) -> dict[int, str]:
    """Every pin of the map (its key) except those of ``but``."""
    used: dict[int, str] = {}
    uart = pins["uart"]
    if uart:
        used.update({uart[1]: "uart", uart[2]: "uart"})
    for key in ("motors", "encoders", "tracking", "sonars"):
        if key != but:
            used.update({p: key for group in pins[key] for p in group if p >= 0})
    if pins["battery"] and but != "battery":
        used[pins["battery"][0]] = "battery"
    return used


def _table(t: PiecewiseLinear | None) -> list[list[float]]:
    if t is None:
        return [[0.0], [1.0]]
    return [[float(x) for x in t.x], [float(y) for y in t.y]]


def _idle_axes(robot: RobotDescription) -> list[float]:
    return courses.idle_axes([w.traction_angle for w in robot.wheels])


PROGRESS_TOLERANCE = 0.10
"""A MOVE short by more than this share on its encoders gets WARN 17 (progress.py): above a wheel
radius a few % off the description's and the encoders' counting, below the 13-16 % a MOVE loses when
a current-limited pair of unequal motors turns the robot (docs/calibration.md, beyond the reach)."""


def _travel(robot: RobotDescription, cpr: list[int], rows: tuple[int, ...] = (0, 1)) -> list[list[float]]:
    """Body travel (m) along x and y (``rows`` 0, 1; row 2: rotation, rad) per encoder count of each
    wheel: the pseudo-inverse of the inverse kinematics, 0 for a wheel without an encoder (then the
    firmware has no progress check and no landing)."""
    forward = robot.forward_rows
    return [
        [
            _inverse_literal(forward[row][i] * 2.0 * math.pi / c, 12) if c > 0 else 0.0
            for i, c in enumerate(cpr)
        ]
        for row in rows
    ]


def _inverse_literal(value: float, digits: int) -> float:
    """A number computed through a least-squares inverse, rounded to ``digits`` and a zero's sign
    dropped: an exact zero of the inverse comes out as a few rounding errors of either sign (the
    SVD's), which the rounding leaves as +-0.0; the literal keeps the number, not that noise."""
    return round(value, digits) + 0.0


LAND_ACCEL = 0.5
"""Share of the description's acceleration limits a closed-loop MOVE (ROTATE) plans its ramp down
with (``land_accel``, up and down): the loop, lagging the ramp, has the rest to catch up with it."""


SPEED_BAND_POWER = 0.05
"""``speed_band`` is the wheel-speed error the loop's P term answers with this share of full power:
after a step the integral grows at half its rate there (larger errors are the rise's lag)."""


STEADY_KI = 2.0
"""``speed_ki_steady`` in ``speed_ki``: the integral learns the floor's steady error twice as fast once
a wheel's target holds still (issue 24: settling within 0.3 s; twice the gains everywhere made the
wheels follow the swings of a host's commands)."""


def _default_k(robot: RobotDescription) -> float:
    """PWM counts per m/s of rim speed from the motor model, when the description gives no K."""
    w = robot.wheels[0]
    m = w.motor
    volts = max(robot.battery.voltage - m.driver_drop, 0.1)
    v_free = volts / (m.torque_constant * m.gear_ratio) * w.radius
    return m.pwm_max / v_free


def _accel_ff(robot: RobotDescription) -> tuple[list[list[float]], list[float]]:
    """The power each wheel needs to accelerate the robot, as the motor current that makes the
    torque and the voltage that drives it through the winding (no back-EMF: the speed's share is
    the feedforward's): ``body_ff``, each wheel's PWM counts per m/s^2 of the body's acceleration
    along x and y and per rad/s^2 of its angular acceleration (the least-norm traction forces that
    give the body its mass times the acceleration and its yaw inertia times the angular one, as
    :func:`~omnibot.control.reach.floor_grip` shares them), and ``wheel_ff``, each wheel's PWM counts
    per rad/s^2 of its own angular acceleration (the wheel's and the rotor's inertia)."""
    wheels = robot.wheels
    scale = (robot.mass, robot.mass, robot.yaw_inertia)
    share = [[v * k for v, k in zip(row, scale, strict=True)] for row in creep_rows(robot).share]
    body, own = [], []
    for i, w in enumerate(wheels):
        m = w.motor
        volts = max(robot.battery.voltage - m.driver_drop, 1e-9)
        counts = m.resistance / (m.torque_constant * m.gear_ratio * m.gear_efficiency) / volts * m.pwm_max
        rim = w.radius * math.cos(w.gamma)
        body.append([_inverse_literal(rim * v * counts, 6) for v in share[i]])  # rim * v: N m per unit accel
        own.append(round((w.inertia + m.rotor_inertia * m.gear_ratio**2) * counts, 6))
    return body, own


def _sonar_axis(robot: RobotDescription, sonar: SonarSpec) -> list[float]:
    """[axis deg, half cone deg, lead cm, half width cm] of a sonar: how far the footprint reaches
    ahead of the sonar along its axis, and to either side of the axis (the sonar stop's geometry)."""
    c, s = math.cos(sonar.angle), math.sin(sonar.angle)
    along = []
    across = []
    for x, y in robot.footprint.outline():
        dx, dy = x - sonar.x, y - sonar.y
        along.append(c * dx + s * dy)
        across.append(abs(-s * dx + c * dy))
    return [
        round(sonar.angle_deg, 6),
        round(sonar.cone_deg / 2.0, 6),
        round(max(0.0, *along) * 100.0, 6),
        round(max(across) * 100.0, 6),
    ]


def build_config(
    robot: RobotDescription,
    *,
    power_min: int | None = None,
    pins: dict[str, Any] | None = None,
    control_period_ms: int = 10,
    slip: SlipParameters | None = None,
) -> dict[str, Any]:
    """The firmware's config dict for a robot (keys in the module docstring); ``slip``: the creep of
    the floor it will drive on (a calibration file's ``surfaces.<floor>.odometry.slip``)."""
    cpr = {e.wheel: e.counts_per_rev for e in robot.encoders.motors}
    encoder_cpr = [int(cpr.get(w.name, 0)) for w in robot.wheels]
    return {
        **_geometry_keys(robot, power_min),
        **_calibration_keys(robot),
        **_limit_keys(robot, encoder_cpr),
        **_landing_keys(robot, encoder_cpr, slip or SlipParameters()),
        **_speed_loop_keys(robot, control_period_ms),
        **_sensor_keys(robot),
        **_battery_keys(robot),
        "pins": pins if pins is not None else default_pins(robot),
    }


def _geometry_keys(robot: RobotDescription, power_min: int | None) -> dict[str, Any]:
    """name ... kl_axes: the robot, its motors' power range and its kinematics."""
    J = robot.inverse_rows
    radius = [float(w.radius) for w in robot.wheels]
    return {
        "name": robot.name,
        "motors": robot.n_wheels,
        "pwm_max": max(w.motor.pwm_max for w in robot.wheels),
        "power_min": int(power_min if power_min is not None else max(w.motor.deadband for w in robot.wheels)),
        "vel_dead_band": True,
        "radius": radius,
        "J": [[float(v) for v in row] for row in J],
        "rim": [[float(v) * r for v in row] for row, r in zip(J, radius, strict=True)],
        "idle_axes": _idle_axes(robot),
        "kl_axes": course_axes(robot.wheels),
    }


def _calibration_keys(robot: RobotDescription) -> dict[str, Any]:
    """k ... reach: the description's calibration as tables (neutral ones without it)."""
    cal = robot.calibration
    n = robot.n_wheels
    if cal and cal.k_l:
        courses = [float(c) for c in cal.k_l.courses_deg]
        kl_tables = [_table(c) for c in cal.k_l.curves]
    else:
        courses, kl_tables = [0.0], [_table(None)]
    motors = cal.motors if cal else None
    if motors is not None and len(motors.offset) != n:
        raise ConfigError(f"{len(motors.offset)} motors for a robot with {n}", key="calibration.motors")
    rollers = cal.rollers if cal else None
    if rollers is not None and len(rollers.cos) != n:
        raise ConfigError(
            f"roller drag for {len(rollers.cos)} wheels on a robot with {n}",
            key="calibration.rollers",
        )
    return {
        "k": _calibration_k(robot),
        "kl_courses": courses,
        "kl_tables": kl_tables,
        "kt": _table(cal.k_t if cal else None),
        "kr": _table(cal.k_r if cal else None),
        "motor_offset": [float(o) for o in motors.offset] if motors else [0.0] * n,
        "motor_gain": [_table(g) for g in motors.gain] if motors else [_table(None)] * n,
        "motor_speed": list(motors.speed) if motors and motors.speed else [0.0] * n,
        "roller_cos": list(rollers.cos) if rollers else [0.0] * n,
        "roller_sin": list(rollers.sin) if rollers else [0.0] * n,
        "roller_coast": (
            [[round(100.0 * x, 6) for x in rollers.coast.x], list(rollers.coast.y)]
            if rollers and rollers.coast
            else [[0.0], [0.0]]
        ),
        "reach": (
            [list(cal.reach.courses_deg), [round(100.0 * v, 6) for v in cal.reach.speed]]
            if cal and cal.reach
            else [[0.0], [0.0]]
        ),
    }


def _calibration_k(robot: RobotDescription) -> float:
    """Calibration K: the description's, else the motors' nominal one."""
    return float(robot.calibration.k) if robot.calibration else _default_k(robot)


def _limit_keys(robot: RobotDescription, encoder_cpr: list[int]) -> dict[str, Any]:
    """roller_dir ... turn: the rollers, the protocol's bounds, the controller and the encoders."""
    _, roller_rows = rows.robot_contact_rows(robot)
    lim = robot.limits
    ctl = robot.controller
    return {
        "roller_dir": [[round(float(v), 9) for v in row[:2]] for row in roller_rows],
        "roller_pitch": [
            round(c / w.rollers.count, 9) for c, w in zip(encoder_cpr, robot.wheels, strict=True)
        ],
        "distance_max_cm": round(lim.distance_max * 100.0, 6),
        "speed_min_cms": round(lim.speed_min * 100.0, 6),
        "speed_max_cms": round(lim.speed_max * 100.0, 6),
        "curvature_max": round(lim.curvature_max * 10.0, 6),
        "rate_max_dps": round(math.degrees(lim.angular_speed_max), 6),
        "queue_capacity": ctl.queue_capacity,
        "line_max": ctl.line_max,
        "baud": ctl.baud,
        "loop_hz": ctl.loop_hz,
        "mode": 2 if ctl.wheel_speed_control and all(encoder_cpr) else 0,
        "encoder_cpr": encoder_cpr,
        "travel": _travel(robot, encoder_cpr),
        "turn": _travel(robot, encoder_cpr, (2,))[0],
    }


def _landing_keys(robot: RobotDescription, encoder_cpr: list[int], slip: SlipParameters) -> dict[str, Any]:
    """slip ... progress_tolerance: the floor's creep and how a closed-loop motion lands."""
    creep = creep_rows(robot)
    lim = robot.limits
    return {
        "slip": [round(slip.roll, 6), round(slip.combined, 6), round(slip.scale, 5)],
        "creep_roll": [[round(float(v), 9) for v in row] for row in creep.roll],
        "creep_rim": [[round(float(v), 9) for v in row] for row in creep.rim],
        "creep_mix": [[_inverse_literal(v, 9) for v in row] for row in creep.mix],
        "land_accel": [
            round(LAND_ACCEL * lim.acceleration_max, 6),
            round(LAND_ACCEL * lim.angular_acceleration_max, 6),
        ],
        "progress_tolerance": PROGRESS_TOLERANCE if all(encoder_cpr) else 0.0,
    }


def _speed_loop_keys(robot: RobotDescription, control_period_ms: int) -> dict[str, Any]:
    """speed_kp ... control_period_ms: the wheel-speed loop's gains and feedforward (default gains
    from calibration K when the description gives none)."""
    kp, ki = robot.controller.speed_kp, robot.controller.speed_ki
    if kp == 0.0 and ki == 0.0:
        radius = [float(w.radius) for w in robot.wheels]
        kr = _calibration_k(robot) * sum(radius) / len(radius)  # feedforward PWM counts per rad/s
        kp, ki = 0.5 * kr, 10.0 * kr
    pwm_max = max(w.motor.pwm_max for w in robot.wheels)
    body_ff, wheel_ff = _accel_ff(robot)
    return {
        "speed_kp": round(kp, 6),
        "speed_ki": round(ki, 6),
        "speed_band": round(SPEED_BAND_POWER * pwm_max / kp, 6) if kp > 0 else 0.0,
        "speed_ki_steady": round(STEADY_KI * ki, 6),
        "body_ff": body_ff,
        "wheel_ff": wheel_ff,
        "control_period_ms": control_period_ms,
    }


def _sensor_keys(robot: RobotDescription) -> dict[str, Any]:
    """tracking ... angular_accel_max_dps2: the sensors and the sonar stop's and braking's limits."""
    lim = robot.limits
    return {
        "tracking": len(robot.encoders.tracking),
        "gyro": robot.gyro is not None,
        "sonar_period_min_ms": [max(60, math.ceil(s.period_min * 1000 - 1e-9)) for s in robot.sonars],
        "sonar_axes": [_sonar_axis(robot, s) for s in robot.sonars],
        "stop_decel_cms2": round(robot.stop_deceleration * 100.0, 6),
        "uncovered_speed_cms": round(robot.uncovered_speed * 100.0, 6),
        "accel_max_cms2": round(lim.acceleration_max * 100.0, 6),
        "angular_accel_max_dps2": round(math.degrees(lim.angular_acceleration_max), 6),
    }


def _battery_keys(robot: RobotDescription) -> dict[str, Any]:
    """battery_mv ... battery_limit_pct: the battery's thresholds and timing in mV, ms and %."""
    battery = robot.battery
    return {
        "battery_mv": [
            round(1000.0 * v) for v in (battery.warn_v, battery.limit_v, battery.stop_v, battery.hysteresis_v)
        ],
        "battery_filter_ms": round(1000.0 * battery.filter_s),
        "battery_delay_ms": round(1000.0 * battery.delay),
        "battery_limit_pct": round(100.0 * battery.limit_power),
    }


def _non_finite(value: Any, where: str) -> str | None:
    """Where in ``value`` (nested lists and dicts) a float is not finite, or None."""
    if isinstance(value, float) and not math.isfinite(value):
        return f"{where} = {value!r}"
    if isinstance(value, list | tuple):
        items: Any = enumerate(value)
    elif isinstance(value, dict):
        items = value.items()
    else:
        return None
    for key, item in items:
        found = _non_finite(item, f"{where}[{key!r}]")
        if found:
            return found
    return None


def config_module_source(config: dict[str, Any]) -> str:
    """The text of ``robot_config.py``: ``CONFIG = {...}`` with plain literals, one key a line.
    A number that is not finite is refused (ConfigError naming it): ``inf`` and ``nan`` are not
    literals, and the board would stop at a NameError."""
    for key, value in config.items():
        found = _non_finite(value, str(key))
        if found:
            raise ConfigError(f"the firmware config cannot hold {found}: every number must be finite")
    lines = [f'"""Firmware config of robot {config["name"]!r}, written by omnibot.firmware.config."""', ""]
    lines.append("CONFIG = {")
    for key, value in config.items():
        lines.append(f"    {key!r}: {value!r},")
    lines.append("}")
    return "\n".join(lines) + "\n"


def write_config_module(config: dict[str, Any], path: str | Path) -> Path:
    """Write ``robot_config.py``; returns its path."""
    path = Path(path)
    path.write_text(config_module_source(config), encoding="utf-8")
    return path


def board_files() -> list[tuple[Path, str]]:
    """(source file, path on the board) of every module the board needs, main.py at the root."""
    files = [
        (SRC_DIR / "omnibot" / "__init__.py", "omnibot/__init__.py"),
        (SRC_DIR / "omnibot" / "protocol" / "__init__.py", "omnibot/protocol/__init__.py"),
        (PACKAGE_DIR / "__init__.py", "omnibot/firmware/__init__.py"),
    ]
    files += [
        (SRC_DIR / "omnibot" / "protocol" / f"{m}.py", f"omnibot/protocol/{m}.py") for m in PROTOCOL_MODULES
    ]
    files += [(PACKAGE_DIR / f"{m}.py", f"omnibot/firmware/{m}.py") for m in BOARD_MODULES]
    files.append((PACKAGE_DIR / "main.py", "main.py"))
    return files


def stage_board(dest: str | Path, config: dict[str, Any]) -> list[Path]:
    """Copy the board's files and ``robot_config.py`` under ``dest``, laid out as on the board."""
    dest = Path(dest)
    out = []
    for src, rel in board_files():
        target = dest / rel
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(src, target)
        out.append(target)
    out.append(write_config_module(config, dest / "robot_config.py"))
    return out


def main(argv: list[str] | None = None) -> int:
    """Stage the board files for a robot (or print its ``robot_config.py``); the exit status."""
    ap = argparse.ArgumentParser(prog="python -m omnibot.firmware.config", description=__doc__.split("\n")[0])
    ap.add_argument("robot", help="preset name or robot description file")
    ap.add_argument("dest", nargs="?", help="directory to stage the board files in")
    ap.add_argument("--print", action="store_true", help="print robot_config.py")
    ap.add_argument("--power-min", type=int, default=None, help="dead band, PWM counts")
    args = ap.parse_args(argv)
    try:
        config = build_config(load_robot(args.robot), power_min=args.power_min)
        config_module_source(config)  # a number the board cannot read fails before a file is written
    except OmnibotError as exc:
        print(f"{ap.prog}: error: {exc}", file=sys.stderr)
        return 2
    if args.print or not args.dest:
        print(config_module_source(config), end="")
    if args.dest:
        for path in stage_board(args.dest, config):
            print(path)
        print(f"copy to the board with: mpremote connect PORT cp -r {args.dest}/. :")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
