"""Seed 000's K_r and K_t read off a calibration section: the powers its firmware would need.

Seed 000's firmware has no motor map: a ROTATE's motors get ``P = K K_r(p) 2 pi F`` whole, the start
of the motors included, and a curved MOVE adds ``P_nt = K K_t(p) V R_c C`` to a motion already under
way. Ours takes each motor's start (its offset), its gain and its speed term out into the motor map
(docs/firmware.md), so a table's K_r is the power *above* the start and cannot be set beside the
seed's Fig. 6 as it is. In the seed's terms, at the uncalibrated power ``p`` (``p = K u``, u the rim
speed)::

    K_r,seed(p) = mean_i |map_i(p K_r(p), u)| / p                    the whole power of a ROTATE
    K_t,seed(p) = mean_i (map_i(a + p K_t(p), v + u) - map_i(a, v)) / p   what the turn adds to a wheel
                                                                     already moving at nominal a, rim v

Without a motor map both are the tables' own values.
"""

from __future__ import annotations

import statistics
from collections.abc import Sequence

from omnibot.calibration.patterns import map_power
from omnibot.errors import ConfigError
from omnibot.robot import CalibrationSpec


def _check(spec: CalibrationSpec, powers: Sequence[float]) -> int:
    """The number of motors of ``spec``'s map (1 without one); ConfigError for what cannot be read."""
    if spec.k_t is None or spec.k_r is None:
        raise ConfigError("seed 000's K_t and K_r need a calibration with both tables")
    if not powers or min(powers) <= 0:
        raise ConfigError(f"powers must be positive PWM counts, got {list(powers)}")
    return len(spec.motors.offset) if spec.motors is not None else 1


def seed_kr(spec: CalibrationSpec, powers: Sequence[float]) -> list[float]:
    """K_r as seed 000's firmware would need it at each uncalibrated power: the ROTATE's whole power,
    each motor's offset and speed term included, over the power."""
    motors = _check(spec, powers)
    assert spec.k_r is not None
    out = []
    for p in powers:
        a, u = p * spec.k_r(p), p / spec.k
        out.append(statistics.fmean(abs(map_power(spec.motors, i, a, u)) for i in range(motors)) / p)
    return out


def seed_kt(spec: CalibrationSpec, powers: Sequence[float], moving: float) -> list[float]:
    """K_t as seed 000's firmware would need it at each uncalibrated power: what the turn adds to the
    power of a wheel already moving at the nominal power ``moving`` (PWM counts, at least 1: a wheel
    under way, past its offset's ramp), over the power."""
    motors = _check(spec, powers)
    assert spec.k_t is not None
    if moving < 1.0:
        raise ConfigError(
            f"the motion the turn is added to needs a nominal power of at least 1, got {moving}"
        )
    v = moving / spec.k
    out = []
    for p in powers:
        a, u = p * spec.k_t(p), p / spec.k
        added = [
            map_power(spec.motors, i, moving + a, v + u) - map_power(spec.motors, i, moving, v)
            for i in range(motors)
        ]
        out.append(statistics.fmean(added) / p)
    return out


__all__ = ["seed_kr", "seed_kt"]
