"""What the client checks before sending: the protocol's ranges and, if known, the robot's limits.

All bounds are in protocol units, the same numbers and comparisons as the firmware's
``limits.py`` (so a command the client lets through is not rejected for its range):

==================  ===========================================================================
distance_max_cm     MOVE: abs(L) < distance_max_cm, or L = +-INF; DELTA: abs(L) < 2 x
speed_min_cms       MOVE: speed_min_cms <= abs(V) <= speed_max_cms; DELTA: abs(V) <= 2 x max
curvature_max       MOVE: abs(C) < curvature_max; DELTA: abs(C) < 2 x
rate_max_dps        ROTATE: 0 < abs(F) < rate_max_dps; VEL: abs(W) < rate_max_dps
pwm_max, motors     POWER: abs(Pi) <= pwm_max, one power per motor
sonar_period_min_ms SONAR: one entry per sonar (numbered 1..k), a period is 0 or >= its entry
has_encoders        MODE bit 1 (closed loop) needs encoders on every motor
==================  ===========================================================================

``Limits()`` knows only the protocol (any robot); :meth:`Limits.from_robot` adds a robot's
limits from its description, through the same config the firmware is built from.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from omnibot.protocol import codes
from omnibot.robot import RobotDescription, load_robot

_NO_LIMIT = float(codes.INT_MAX + 1)


@dataclass(frozen=True)
class Limits:
    """Command bounds in protocol units; None where the robot is unknown (not checked)."""

    distance_max_cm: float = float(codes.INF)
    speed_min_cms: float = 1.0
    speed_max_cms: float = float(codes.INT_MAX)
    curvature_max: float = _NO_LIMIT
    rate_max_dps: float = _NO_LIMIT
    pwm_max: int = codes.POWER_MAX
    motors: int | None = None
    sonar_period_min_ms: tuple[int, ...] | None = None
    has_encoders: bool | None = None
    robot: str | None = None
    """The robot's name, None for protocol-only limits."""

    @classmethod
    def from_config(cls, config: dict[str, Any]) -> Limits:
        """Limits from a firmware config dict (:func:`omnibot.firmware.config.build_config`)."""
        return cls(
            distance_max_cm=float(config["distance_max_cm"]),
            speed_min_cms=float(config["speed_min_cms"]),
            speed_max_cms=float(config["speed_max_cms"]),
            curvature_max=float(config["curvature_max"]),
            rate_max_dps=float(config["rate_max_dps"]),
            pwm_max=int(config["pwm_max"]),
            motors=int(config["motors"]),
            sonar_period_min_ms=tuple(max(60, int(p)) for p in config["sonar_period_min_ms"]),
            has_encoders=all(int(c) > 0 for c in config["encoder_cpr"]),
            robot=str(config["name"]),
        )

    @classmethod
    def from_robot(cls, robot: RobotDescription | str) -> Limits:
        """Limits of a robot description (or a preset name / description file)."""
        from omnibot.firmware.config import build_config

        description = load_robot(robot) if isinstance(robot, str) else robot
        return cls.from_config(build_config(description))
