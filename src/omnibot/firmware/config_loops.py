"""Host side (CPython): the config's keys of the closed loops: the encoders' travel, the landing, the speed loop.

``travel`` and ``turn`` (the least-squares forward kinematics per encoder count), the floor's creep
and the landing's ramps (``slip`` ... ``progress_tolerance``, landing.py, progress.py) and the
wheel-speed loop's gains and acceleration feedforward (``speed_kp`` ... ``control_period_ms``,
speedctl.py, motion_drive.py).
"""

from __future__ import annotations

import math
from typing import Any

from omnibot.estimation import SlipParameters, creep_rows
from omnibot.firmware.config_calibration import calibration_k
from omnibot.robot import RobotDescription

PROGRESS_TOLERANCE = 0.10
"""A MOVE short by more than this share on its encoders gets WARN 17 (progress.py): above a wheel
radius a few % off the description's and the encoders' counting, below the 13-16 % a MOVE loses when
a current-limited pair of unequal motors turns the robot (docs/calibration.md, beyond the reach)."""


def travel(robot: RobotDescription, cpr: list[int], rows: tuple[int, ...] = (0, 1)) -> list[list[float]]:
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


def accel_ff(robot: RobotDescription) -> tuple[list[list[float]], list[float]]:
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


def landing_keys(robot: RobotDescription, encoder_cpr: list[int], slip: SlipParameters) -> dict[str, Any]:
    """slip ... progress_tolerance: the floor's creep and how a closed-loop motion lands."""
    creep = creep_rows(robot)
    lim = robot.limits
    return {
        "slip": [round(slip.roll, 6), round(slip.combined, 6), round(slip.scale, 5), round(slip.ramp, 7)],
        "creep_roll": [[round(float(v), 9) for v in row] for row in creep.roll],
        "creep_rim": [[round(float(v), 9) for v in row] for row in creep.rim],
        "creep_mix": [[_inverse_literal(v, 9) for v in row] for row in creep.mix],
        "land_accel": [
            round(LAND_ACCEL * lim.acceleration_max, 6),
            round(LAND_ACCEL * lim.angular_acceleration_max, 6),
        ],
        "progress_tolerance": PROGRESS_TOLERANCE if all(encoder_cpr) else 0.0,
    }


def speed_loop_keys(robot: RobotDescription, control_period_ms: int) -> dict[str, Any]:
    """speed_kp ... control_period_ms: the wheel-speed loop's gains and feedforward (default gains
    from calibration K when the description gives none)."""
    kp, ki = robot.controller.speed_kp, robot.controller.speed_ki
    if kp == 0.0 and ki == 0.0:
        radius = [float(w.radius) for w in robot.wheels]
        kr = calibration_k(robot) * sum(radius) / len(radius)  # feedforward PWM counts per rad/s
        kp, ki = 0.5 * kr, 10.0 * kr
    pwm_max = max(w.motor.pwm_max for w in robot.wheels)
    body_ff, wheel_ff = accel_ff(robot)
    return {
        "speed_kp": round(kp, 6),
        "speed_ki": round(ki, 6),
        "speed_band": round(SPEED_BAND_POWER * pwm_max / kp, 6) if kp > 0 else 0.0,
        "speed_ki_steady": round(STEADY_KI * ki, 6),
        "body_ff": body_ff,
        "wheel_ff": wheel_ff,
        "control_period_ms": control_period_ms,
    }
