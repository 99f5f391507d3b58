"""Host side (CPython): the firmware's plain config dict from a robot description, and board files.

The firmware reads only plain literals (MicroPython has no pydantic or numpy), so everything derived
from the description is computed here: the rim-speed matrix (inverse kinematics times wheel radius),
the idle axes for folding the course, calibration tables as lists, limits in protocol units. The
keys' groups have their modules: ``config_calibration.py`` (``k`` ... ``reach``), ``config_loops.py``
(``travel``, ``turn``, ``slip`` ... ``control_period_ms``: the encoders, the landing, the speed
loop) and ``config_pins.py`` (``pins``); ``config_staging.py`` writes ``robot_config.py`` and lays
out the board's files.

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
slip                        the floor's wheel creep [roll m/s, combined, scale, ramp s^3/m]
                            (estimation/slip.py, from ``omnibot calibrate``'s slip runs; CAL table 9);
                            [0, 0, 1, 0]: none (three values: a config from before the ramp, 0)
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
import sys
from typing import Any

from omnibot.errors import OmnibotError
from omnibot.estimation import SlipParameters
from omnibot.firmware.config_calibration import calibration_keys
from omnibot.firmware.config_loops import landing_keys, speed_loop_keys, travel
from omnibot.firmware.config_pins import default_pins
from omnibot.firmware.config_staging import (
    board_files,
    config_module_source,
    stage_board,
    write_config_module,
)
from omnibot.robot import RobotDescription, SonarSpec, course_axes, courses, load_robot, rows

__all__ = [
    "board_files",
    "build_config",
    "config_module_source",
    "default_pins",
    "main",
    "stage_board",
    "write_config_module",
]
"""The host's face of the firmware: the config dict (here), its pin map (config_pins.py) and the
board's files (config_staging.py), as the commands, the simulator and the tests take them."""


def _idle_axes(robot: RobotDescription) -> list[float]:
    return courses.idle_axes([w.traction_angle for w in robot.wheels])


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
        **calibration_keys(robot),
        **_limit_keys(robot, encoder_cpr),
        **landing_keys(robot, encoder_cpr, slip or SlipParameters()),
        **speed_loop_keys(robot, control_period_ms),
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
        "travel": travel(robot, encoder_cpr),
        "turn": travel(robot, encoder_cpr, (2,))[0],
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
