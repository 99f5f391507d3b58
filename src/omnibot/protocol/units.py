"""Conversions between the protocol's integer units and SI (the library's units).

Protocol units: cm, cm/s, degrees, degrees/s, curvature 1/(1000 cm) (C = 100 is a 10 cm radius),
ms, gyro rate 0.01 deg/s, heading 0.01 deg, battery mV, calibration factors x 1000, K in 0.001 PWM
counts per cm/s. ``to_*`` functions round to the nearest protocol integer.
"""

from __future__ import annotations

import math

from omnibot.protocol import codes


def to_cm(metres: float) -> int:
    """Metres (or m/s) to whole cm (cm/s)."""
    return round(metres * 100.0)


def from_cm(cm: float) -> float:
    """cm (or cm/s) to metres (m/s)."""
    return cm / 100.0


def to_deg(radians: float) -> int:
    """Radians (or rad/s) to whole degrees (degrees/s)."""
    return round(math.degrees(radians))


def from_deg(degrees: float) -> float:
    """Degrees (or degrees/s) to radians (rad/s)."""
    return math.radians(degrees)


def to_curvature(per_metre: float) -> int:
    """Curvature 1/m to the protocol's 1/(1000 cm): C = 10 * kappa."""
    return round(per_metre * 10.0)


def from_curvature(c: float) -> float:
    """The protocol's curvature C to 1/m."""
    return c / 10.0


def to_ms(seconds: float) -> int:
    """Seconds to whole ms."""
    return round(seconds * 1000.0)


def from_ms(ms: float) -> float:
    """ms to seconds."""
    return ms / 1000.0


def to_centideg(radians: float) -> int:
    """Radians (or rad/s) to 0.01 degree (0.01 deg/s): TEL gyro rate and heading."""
    return round(math.degrees(radians) * 100.0)


def from_centideg(value: float) -> float:
    """0.01 degree (0.01 deg/s) to radians (rad/s)."""
    return math.radians(value / 100.0)


def from_mv(mv: float) -> float:
    """mV to volts."""
    return mv / 1000.0


def to_milli(factor: float) -> int:
    """A calibration factor to its CAL integer (x 1000)."""
    return round(factor * codes.CAL_SCALE)


def from_milli(value: float) -> float:
    """A CAL integer to its factor."""
    return value / codes.CAL_SCALE


def to_cal_k(pwm_per_mps: float) -> int:
    """K in PWM counts per m/s of rim speed to its CAL integer (0.001 counts per cm/s): x 10."""
    return round(pwm_per_mps * 10.0)


def from_cal_k(value: float) -> float:
    """The CAL integer of K to PWM counts per m/s of rim speed."""
    return value / 10.0


def clamp16(value: int) -> int:
    """Clamp an integer to the 16-bit range of command parameters."""
    return max(codes.INT_MIN, min(codes.INT_MAX, value))
