"""What a speed profile must keep within: the robot's speed, acceleration and traction limits
(:class:`MotionLimits`, built from a description, on a floor or not), for
:func:`~omnibot.control.paths.profile.time_optimal_profile`."""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

import numpy as np

from omnibot.control.paths.path import FloatArray
from omnibot.robot import RobotDescription

if TYPE_CHECKING:
    from omnibot.control.reach import FloorReach

Grip = tuple[tuple[float, ...], tuple[float, ...]]
"""(speeds m/s, fractions): the share of the accelerations a floor's grip leaves at each speed."""


def grip_share(grip: Grip | None, speed: FloatArray | float) -> FloatArray:
    """The share of the accelerations ``grip`` leaves at each ``speed`` (m/s), interpolated; 1
    without a floor (``grip`` None): the planner's and teleop's ramps read it alike."""
    if grip is None:
        return np.ones_like(speed, dtype=np.float64)
    speeds, fractions = grip
    return np.asarray(np.interp(speed, speeds, fractions), dtype=np.float64)


@dataclass(frozen=True)
class MotionLimits:
    """Speed and acceleration limits for planning (SI)."""

    v_max: float
    a_max: float
    w_max: float
    alpha_max: float
    a_lat: float | None = None
    """Sideways (centripetal) acceleration limit; None: a_max (a friction circle)."""
    wheels: tuple[tuple[float, float, float], ...] | None = None
    """Per wheel, the fraction of its free-running speed one unit of body twist (vx, vy, w) needs
    (:func:`omnibot.control.reach.wheel_rows`); None: no wheel-speed cap."""
    wheel_use: float = 1.0
    """The fraction of the wheels' free-running speed (and of the floor's reach) the profile may use."""
    floor: FloorReach | None = None
    """The motors' reach on a floor for every body twist (:func:`omnibot.control.reach.floor_reach`:
    translation along a body course and a turn together): the twist is capped at ``floor_use`` of
    it; None: no floor cap."""
    floor_use: float = 1.0
    """The fraction of the floor's reach the profile may use: apart from ``wheel_use``, whose margin
    also stands for the floor's load, which the reach already carries."""
    grip: Grip | None = None
    """(speeds, fractions): the fraction of the accelerations (and of the lateral one) the wheels'
    grip leaves beside a floor's drag at each speed (:func:`omnibot.control.reach.floor_grip`),
    interpolated; None: all of them."""
    course_rate: float | None = None
    """rad/s: the fastest the direction of travel may turn, v |kappa| (the wheels' sideways creep,
    which the odometry does not see, grows with v^2 kappa, so the drift per metre with v kappa:
    :func:`omnibot.control.reach.floor_course_rate`); None: no cap."""

    def __post_init__(self) -> None:
        for name in ("v_max", "a_max", "w_max", "alpha_max"):
            value = getattr(self, name)
            if not (value > 0 and math.isfinite(value)):
                raise ValueError(f"motion limit {name} must be a positive number, got {value}")
        if self.a_lat is not None and not self.a_lat > 0:
            raise ValueError(f"motion limit a_lat must be positive, got {self.a_lat}")
        if not 0 < self.wheel_use <= 1:
            raise ValueError(f"motion limit wheel_use must be in (0, 1], got {self.wheel_use}")
        if not 0 < self.floor_use <= 1:
            raise ValueError(f"motion limit floor_use must be in (0, 1], got {self.floor_use}")
        if self.course_rate is not None and not self.course_rate > 0:
            raise ValueError(f"motion limit course_rate must be positive, got {self.course_rate}")

    @property
    def lateral(self) -> float:
        """Largest lateral (centripetal) acceleration, m/s²: ``a_lat``, or ``a_max`` when unset."""
        return self.a_max if self.a_lat is None else self.a_lat

    @classmethod
    def from_robot(
        cls, robot: RobotDescription, speed: float | None = None, surface: str | None = None
    ) -> MotionLimits:
        """The robot's own limits, the speed capped at ``speed`` m/s when given, with its wheels'
        free-running speeds and, given a ``surface``, the reach the floor's load leaves its motors
        (:mod:`omnibot.control.reach`)."""
        from omnibot.control.reach import wheel_rows

        lim = robot.limits
        v = lim.speed_max if speed is None else min(speed, lim.speed_max)
        floor, grip = (None, None) if surface is None else _floor_tables(robot, surface, v)
        return cls(
            v,
            lim.acceleration_max,
            lim.angular_speed_max,
            lim.angular_acceleration_max,
            wheels=wheel_rows(robot),
            floor=floor,
            grip=grip,
        )

    def with_wheel_use(self, fraction: float) -> MotionLimits:
        """These limits using at most ``fraction`` of the wheels' free-running speed."""
        return replace(self, wheel_use=fraction)

    def scaled(self, factor: float, speed_factor: float = 1.0) -> MotionLimits:
        """Accelerations times ``factor``, speeds times ``speed_factor`` (a planning margin)."""
        return replace(
            self,
            v_max=self.v_max * speed_factor,
            w_max=self.w_max * speed_factor,
            a_max=self.a_max * factor,
            alpha_max=self.alpha_max * factor,
            a_lat=None if self.a_lat is None else self.a_lat * factor,
        )

    def grip_at(self, speed: FloatArray) -> FloatArray:
        """The fraction of the accelerations the floor's grip leaves at each ``speed`` (m/s; 1
        without a floor)."""
        return grip_share(self.grip, speed)

    def with_turn_rate(self, w_max: float) -> MotionLimits:
        """These limits with the turn rate capped at ``w_max`` rad/s (never raised)."""
        return replace(self, w_max=min(self.w_max, w_max))

    def reach(self, twist: FloatArray, wheel_use: float = 1.0, floor_use: float = 1.0) -> FloatArray:
        """The largest factor each body twist of ``twist`` (k, 3: vx, vy, w) may be multiplied by
        with no wheel beyond ``wheel_use`` of its free-running speed and the twist within
        ``floor_use`` of the floor's reach (inf where neither caps it)."""
        cap = np.full(len(twist), math.inf)
        with np.errstate(divide="ignore"):
            if self.wheels is not None:
                need = np.max(np.abs(twist @ np.array(self.wheels).T), axis=1)
                cap = np.where(need > 1e-12, wheel_use / np.maximum(need, 1e-12), math.inf)
        if self.floor is not None:
            cap = np.minimum(cap, floor_use * self.floor.multiple(twist))
        return cap


_REACH_CACHE: dict[tuple[str, str], FloorReach] = {}
_GRIP_CACHE: dict[tuple[str, str, float], Grip] = {}


def grip_table(robot: RobotDescription, surface: str, top: float) -> Grip:
    """The share of ``robot``'s accelerations the grip on ``surface`` leaves at each speed up to
    ``top`` m/s (:func:`~omnibot.control.reach.floor_grip`; computed once per description, floor and
    speed): what the planner's :meth:`MotionLimits.grip_at` and teleop's ramp read."""
    from omnibot.control.reach import floor_grip

    key = (robot.model_dump_json(), surface, top)
    if key not in _GRIP_CACHE:
        _GRIP_CACHE[key] = floor_grip(robot, surface, top)
    return _GRIP_CACHE[key]


def _floor_tables(robot: RobotDescription, surface: str, top: float) -> tuple[FloorReach, Grip]:
    """The robot's reach on ``surface`` (computed once per description and floor) and its grip table
    up to ``top`` m/s (:func:`grip_table`): :func:`omnibot.control.reach.floor_reach`."""
    from omnibot.control.reach import floor_reach

    key = (robot.model_dump_json(), surface)
    if key not in _REACH_CACHE:
        _REACH_CACHE[key] = floor_reach(robot, surface)
    return _REACH_CACHE[key], grip_table(robot, surface, top)
