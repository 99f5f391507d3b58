"""A robot whose true parameters differ from its description, for calibrating in the simulator.

A perturbation is a short text: ``;``-separated ``key=values``; one value scales every wheel, a
comma-separated list scales each wheel in the description's order::

    radius=1.05;torque_constant=1.1,0.9,0.9,1.1

``radius`` scales wheel radii; any motor key (``resistance``, ``torque_constant``,
``friction_static``, ...) scales that key of each wheel's motor (a per-wheel override, as a
description's ``wheels[i].motor`` would write it). :data:`ACCEPTANCE` is the acceptance test's robot.
"""

from __future__ import annotations

import difflib

from omnibot.errors import ConfigError
from omnibot.robot import MotorSpec, RobotDescription, parse_description

ACCEPTANCE = "radius=1.05;torque_constant=1.1,0.9,0.9,1.1"
"""Wheel radius +5 %, motors +-10 % apart: on omni4 each opposite pair (the two motors of a
course-0 or course-90 run) has one strong and one weak motor."""

_MOTOR_KEYS = sorted(
    k for k, f in MotorSpec.model_fields.items() if f.annotation in (float, int) and k != "pwm_bits"
)
KEYS = ["radius", *_MOTOR_KEYS]


def parse_perturbation(spec: str, wheels: int) -> dict[str, list[float]]:
    """``key=values`` pairs -> per-wheel scale factors; ConfigError naming what is wrong."""
    out: dict[str, list[float]] = {}
    for part in (p.strip() for p in spec.split(";")):
        if not part:
            continue
        key, sep, values = part.partition("=")
        key = key.strip()
        if not sep:
            raise ConfigError(f"expected key=value, got {part!r}", key="--perturb")
        if key not in KEYS:
            close = [k for k in KEYS if k.startswith(key)] or difflib.get_close_matches(key, KEYS, n=1)
            hint = f"; did you mean '{close[0]}'?" if close else f"; expected one of: {', '.join(KEYS)}"
            raise ConfigError(f"unknown key '{key}'{hint}", key="--perturb")
        try:
            scales = [float(v) for v in values.split(",")]
        except ValueError:
            raise ConfigError(f"{key}: expected numbers, got {values!r}", key="--perturb") from None
        if len(scales) == 1:
            scales *= wheels
        if len(scales) != wheels or not all(s > 0 for s in scales):
            raise ConfigError(
                f"{key}: expected one positive factor or {wheels} (one per wheel), got {values!r}",
                key="--perturb",
            )
        out[key] = scales
    return out


def perturbed_robot(robot: RobotDescription, spec: str) -> RobotDescription:
    """``robot`` with the perturbation applied (its calibration section unchanged)."""
    factors = parse_perturbation(spec, robot.n_wheels)
    data = robot.model_dump(exclude_none=True)
    for i, wheel in enumerate(data["wheels"]):
        for key, scales in factors.items():
            if key == "radius":
                wheel["radius"] *= scales[i]
            else:
                value = wheel["motor"][key] * scales[i]
                wheel["motor"][key] = round(value) if key == "deadband" else value
    return parse_description(data, f"{robot.name} perturbed ({spec})")
