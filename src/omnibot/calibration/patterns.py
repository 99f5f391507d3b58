"""Motor power patterns and course folding for calibration runs (pure functions, any wheel layout).

Seed 000 drives its calibration runs with raw motor powers: course 0 is two opposite motors at +P
and -P, course 45 all four at +-P, rotation all four at +P. Generalised through the kinematics:
the pattern of a course is the rim speed each wheel needs for a unit translation along it (the
firmware's ``rim`` matrix, inverse kinematics times wheel radius), scaled so that the busiest motor
gets P. For omni4 this is exactly the seed's patterns.

The firmware looks K_l up at the course *folded* onto 0..fold_max (the angle to the nearest of its
course axes, :func:`omnibot.firmware.calibration.fold_course`: the idle axes on omni wheels, the body's
x axis on a mecanum base, :mod:`omnibot.robot.courses`); every raw course ``axis +- c`` folds to ``c``.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

from omnibot.firmware.calibration import fold_course, map_motor
from omnibot.firmware.config import build_config
from omnibot.firmware.power import roller_terms
from omnibot.robot import MotorMapSpec, RobotDescription, courses


@dataclass(frozen=True)
class Geometry:
    """What the firmware derives from a description and calibration needs: rim matrix and idle axes."""

    rim: tuple[tuple[float, float, float], ...]
    """Rim speed (m/s) of each wheel per unit twist (vx, vy, w)."""
    idle_axes: tuple[float, ...]
    """Directions (degrees, 0..180) of travel along which some wheel stands still."""
    pwm_max: int
    roller_dir: tuple[tuple[float, float], ...] = ()
    """Each wheel's rollers' rolling direction (body frame)."""
    roller_pitch: tuple[float, ...] = ()
    """Encoder counts per roller pitch of each wheel (0: no encoder)."""
    course_axes: tuple[float, ...] = ()
    """The axes (degrees) K_l's and the reach's courses fold from (none given: the idle axes)."""

    @classmethod
    def of(cls, robot: RobotDescription) -> Geometry:
        """The geometry of ``robot`` as the firmware sees it (from its generated config)."""
        cfg = build_config(robot)
        rim = tuple((float(r[0]), float(r[1]), float(r[2])) for r in cfg["rim"])
        return cls(
            rim=rim,
            idle_axes=tuple(float(a) for a in cfg["idle_axes"]),
            pwm_max=int(cfg["pwm_max"]),
            roller_dir=tuple((float(d[0]), float(d[1])) for d in cfg["roller_dir"]),
            roller_pitch=tuple(float(p) for p in cfg["roller_pitch"]),
            course_axes=tuple(float(a) for a in cfg["kl_axes"]),
        )

    @property
    def motors(self) -> int:
        """The number of driven motors."""
        return len(self.rim)

    @property
    def fold_axes(self) -> tuple[float, ...]:
        """The axes the firmware folds K_l's courses from: :attr:`course_axes`, else the idle axes."""
        return self.course_axes or self.idle_axes

    @property
    def fold_marker(self) -> tuple[float, ...] | None:
        """A calibration section's ``fold_axes_deg`` on this robot: its fold axes where they are not
        the idle axes (a mecanum base), else None (absent: the idle axes)."""
        if courses.same_axes(self.fold_axes, self.idle_axes):
            return None
        return self.fold_axes

    @property
    def fold_max(self) -> float:
        """Largest folded course (degrees): half the widest gap between neighbouring fold axes."""
        return courses.fold_max(self.fold_axes)

    @property
    def idle_fold_max(self) -> float:
        """Half the widest gap between neighbouring idle axes (degrees): halfway between two."""
        return courses.fold_max(self.idle_axes)

    def fold(self, course_deg: float) -> float:
        """The course (degrees) folded as the firmware folds it for K_l."""
        return fold_course(course_deg, list(self.fold_axes))

    def raw_courses(self, folded_deg: float, count: int) -> list[float]:
        """``count`` raw courses (degrees, 0..360) that fold to ``folded_deg``, spread round the circle.

        The candidates are ``axis + folded`` for every fold axis and its opposite, so they alternate
        between wheel groups and directions (and runs on them roughly return the robot to its start);
        when those are fewer than ``count`` (one fold axis: a mecanum base), their mirror images too
        (:meth:`every_raw_course`).
        """
        bases = self._bases()
        candidates = [round((b + folded_deg) % 360.0, 6) for b in bases]
        if count > len(candidates):
            candidates = self.every_raw_course(folded_deg)
        if count >= len(candidates):
            return candidates
        step = len(candidates) / count
        return [candidates[int(k * step)] for k in range(count)]

    def every_raw_course(self, folded_deg: float) -> list[float]:
        """Every raw course (degrees, 0..360) that folds to ``folded_deg``: ``axis + folded`` for each
        fold axis and its opposite, then ``axis - folded`` (its mirror image), so each half returns
        the robot to its start and a course's opposite is in the same half."""
        bases = self._bases()
        out: list[float] = []
        for sign in (1.0, -1.0):
            for b in bases:
                c = round((b + sign * folded_deg) % 360.0, 6)
                if c not in out:
                    out.append(c)
        return out

    def _bases(self) -> list[float]:
        """Every fold axis and its opposite (degrees, 0..360), round the circle."""
        return sorted({round((a + s) % 360.0, 6) for a in self.fold_axes for s in (0.0, 180.0)})

    def translation_rim(self, course_deg: float) -> list[float]:
        """Rim speed of each wheel for 1 m/s along ``course_deg``."""
        c, s = math.cos(math.radians(course_deg)), math.sin(math.radians(course_deg))
        return [r[0] * c + r[1] * s for r in self.rim]

    def idle_wheels(self, course_deg: float) -> list[int]:
        """The wheels that do not turn on a straight run along the course."""
        rims = self.translation_rim(course_deg)
        peak = max(abs(v) for v in rims)
        return [i for i, v in enumerate(rims) if abs(v) < 1e-6 * peak]

    def roller_terms(self, course_deg: float, counts: Sequence[int]) -> tuple[list[float], list[float]]:
        """Each wheel's roller drag terms (cos, sin) at encoder ``counts`` for travel along the course,
        as the firmware computes them (:func:`omnibot.firmware.power.roller_terms`)."""
        n = self.motors
        fc, fs = [0.0] * n, [0.0] * n
        c, s = math.cos(math.radians(course_deg)), math.sin(math.radians(course_deg))
        dirs = [list(d) for d in self.roller_dir]
        roller_terms(dirs, list(self.roller_pitch), list(counts), c, s, fc, fs)
        return fc, fs

    def rotation_rim(self) -> list[float]:
        """Rim speed of each wheel for 1 rad/s counter-clockwise."""
        return [r[2] for r in self.rim]

    def translation_factor(self, course_deg: float) -> float:
        """Rim speed of the busiest wheel per m/s along the course: the firmware's K_l power argument
        is K times this times the speed."""
        return max(abs(v) for v in self.translation_rim(course_deg))

    def rotation_factor(self) -> float:
        """Rim speed of the busiest wheel per rad/s of rotation."""
        return max(abs(v) for v in self.rotation_rim())


Rate = Callable[[float, float], float]
"""(nominal power of the busiest motor, folded course in degrees) -> that motor's rim speed (m/s) the
power is expected to give: what the motor map's speed term needs for a raw POWER pattern."""


def map_power(motors: MotorMapSpec | None, i: int, a: float, u: float = 0.0) -> float:
    """Motor i's power for the nominal power ``a`` at rim speed ``u`` (m/s): the firmware's formula
    (:func:`omnibot.firmware.calibration.map_motor`) with the map's gain tables."""
    if motors is None or a == 0.0:
        return a
    return map_motor(motors.offset[i], motors.gain[i](abs(a)), motors.speed_term(i), a, u)


def apply_map(
    motors: MotorMapSpec | None, nominal: Sequence[float], pwm_max: int, speeds: Sequence[float] | None = None
) -> list[int]:
    """The integer powers the firmware would send for nominal powers at rim ``speeds`` (m/s; none: 0)
    (clipped, not rescaled)."""
    us = speeds if speeds is not None else [0.0] * len(nominal)
    return [
        max(-pwm_max, min(pwm_max, round(map_power(motors, i, a, u))))
        for i, (a, u) in enumerate(zip(nominal, us, strict=True))
    ]


def top_power(motors: MotorMapSpec | None, pwm_max: int) -> int:
    """The largest nominal power the map does not saturate for any motor."""
    if motors is None:
        return pwm_max
    top = pwm_max
    for o, g in zip(motors.offset, motors.gain, strict=True):
        top = min(top, math.floor((pwm_max - o) / max(g.y)))
    return max(top, 1)


def scaled_pattern(
    rims: list[float], power: int, motors: MotorMapSpec | None = None, pwm_max: int = 255, speed: float = 0.0
) -> list[int]:
    """Integer powers proportional to ``rims`` with the busiest motor at nominal ``power`` (sign kept),
    through the motor map when there is one, the busiest wheel's rim at ``speed`` m/s."""
    peak = max(abs(v) for v in rims)
    if peak <= 0.0:
        raise ValueError("a pattern needs at least one wheel that turns")
    if motors is None:
        return [round(power * v / peak) for v in rims]
    return apply_map(motors, [power * v / peak for v in rims], pwm_max, [speed * v / peak for v in rims])


def course_pattern(
    geometry: Geometry,
    course_deg: float,
    power: int,
    motors: MotorMapSpec | None = None,
    rate: Rate | None = None,
) -> list[int]:
    """Seed 000's straight-run pattern generalised: busiest motor at ``power`` along the course (its
    rim speed for the map's speed term from ``rate``; none: 0)."""
    speed = rate(power, geometry.fold(course_deg)) if rate is not None else 0.0
    return scaled_pattern(geometry.translation_rim(course_deg), power, motors, geometry.pwm_max, speed)


def rotation_pattern(
    geometry: Geometry,
    power: int,
    ccw: bool = True,
    motors: MotorMapSpec | None = None,
    rate: Rate | None = None,
) -> list[int]:
    """Rotation in place, busiest motor at ``power``; ``ccw`` False turns clockwise (the rim speed for
    the map's speed term from ``rate`` at course 0, where no wheel is loaded by a course; none: 0)."""
    rims = geometry.rotation_rim()
    speed = rate(power, 0.0) if rate is not None else 0.0
    return scaled_pattern(rims if ccw else [-v for v in rims], power, motors, geometry.pwm_max, speed)
