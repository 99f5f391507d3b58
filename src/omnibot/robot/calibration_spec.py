"""A robot description's calibration section: seed 000's factor tables, the per-motor map, the roller
drag and the reach, and moving K_l and the reach onto a robot's course axes."""

from __future__ import annotations

from typing import Any

from pydantic import Field, model_validator

from omnibot.robot import courses as fold_axes
from omnibot.robot.parts import WheelSpec
from omnibot.robot.spec import Spec


class PiecewiseLinear(Spec):
    """y(x) by linear interpolation between knots, held constant outside them."""

    x: tuple[float, ...]
    y: tuple[float, ...]

    @model_validator(mode="after")
    def _check(self) -> PiecewiseLinear:
        if len(self.x) != len(self.y) or not self.x:
            raise ValueError("x and y need the same, non-zero number of knots")
        if any(b <= a for a, b in zip(self.x, self.x[1:], strict=False)):
            raise ValueError("x must increase strictly")
        return self

    def __call__(self, value: float) -> float:
        """y at ``value``: linear between knots, the end values outside them."""
        xs, ys = self.x, self.y
        if value <= xs[0]:
            return ys[0]
        for i in range(1, len(xs)):
            if value <= xs[i]:
                t = (value - xs[i - 1]) / (xs[i] - xs[i - 1])
                return ys[i - 1] + t * (ys[i] - ys[i - 1])
        return ys[-1]


class CourseTable(Spec):
    """K_l(power, course): one power curve per folded course (seed 000, Fig. 7: 0..45 degrees on omni4;
    0..90 on a mecanum base, :mod:`omnibot.robot.courses`)."""

    courses_deg: tuple[float, ...]
    curves: tuple[PiecewiseLinear, ...]

    @model_validator(mode="after")
    def _check(self) -> CourseTable:
        if len(self.courses_deg) != len(self.curves) or not self.curves:
            raise ValueError("courses_deg and curves need the same, non-zero length")
        if any(b <= a for a, b in zip(self.courses_deg, self.courses_deg[1:], strict=False)):
            raise ValueError("courses_deg must increase strictly")
        return self


SPEED_TERM_MAX = 3276.7
"""PWM counts per m/s: the largest speed term CAL can carry (0.1 counts per m/s in 16 bits)."""


class MotorMapSpec(Spec):
    """Per-motor map of the nominal power a at rim speed u (m/s):
    ``sign(a) (offset_i + gain_i(|a|) |a|) + speed_i u`` (firmware). With a constant gain it is the
    two-number motor model: the gain scales the load's share of the power, the speed term corrects
    the back-EMF's (docs/calibration.md, motor map)."""

    offset: tuple[float, ...] = Field(description="dead-band offset of each motor, PWM counts")
    gain: tuple[PiecewiseLinear, ...] = Field(description="gain of each motor over the nominal power")
    speed: tuple[float, ...] | None = Field(
        default=None, description="speed term of each motor, PWM counts per m/s of its rim speed (none: 0)"
    )

    @model_validator(mode="after")
    def _check(self) -> MotorMapSpec:
        if len(self.offset) != len(self.gain) or not self.offset:
            raise ValueError("offset and gain need one entry per motor")
        if any(o < 0 for o in self.offset) or any(y <= 0 for g in self.gain for y in g.y):
            raise ValueError("offsets must be >= 0 and gains > 0")
        if self.speed is not None:
            if len(self.speed) != len(self.offset):
                raise ValueError(
                    f"speed needs one entry per motor ({len(self.offset)}), got {len(self.speed)}"
                )
            if any(abs(s) > SPEED_TERM_MAX for s in self.speed):
                raise ValueError(f"speed terms must lie within +-{SPEED_TERM_MAX} PWM counts per m/s")
        return self

    def speed_term(self, i: int) -> float:
        """Motor i's speed term, PWM counts per m/s (0 without one)."""
        return self.speed[i] if self.speed is not None else 0.0


class RollerDragSpec(Spec):
    """How the idle wheels' rollers drag with the wheel's angle (firmware's roller term, one entry per
    wheel): the drag ``cos_i cos(n phi_i) + sin_i sin(n phi_i)`` (PWM counts of the busiest motor) at
    wheel angle phi_i from the controller's encoder origin, n its roller count. Zero mean: the mean drag
    is in K_l."""

    cos: tuple[float, ...] = Field(description="cosine coefficient of each wheel, PWM counts")
    sin: tuple[float, ...] = Field(description="sine coefficient of each wheel, PWM counts")
    coast: PiecewiseLinear | None = Field(
        default=None,
        description="s the drag acts beyond a MOVE (it brakes the coast too; < 0: less) against the speed in m/s",
    )

    @model_validator(mode="after")
    def _check(self) -> RollerDragSpec:
        if len(self.cos) != len(self.sin) or not self.cos:
            raise ValueError("cos and sin need one entry per wheel")
        if self.coast is not None and min(self.coast.x) < 0:
            raise ValueError("coast: speeds must be >= 0")
        return self


class ReachSpec(Spec):
    """The calibrated reach: the fastest open-loop MOVE (of the calibration's reference length) that
    lands within the calibration's goal on each folded course, as the calibration measured it
    (docs/calibration.md); linear between the courses, held outside them."""

    courses_deg: tuple[float, ...] = Field(description="folded courses, degrees (0..90, increasing)")
    speed: tuple[float, ...] = Field(description="m/s on each course")

    @model_validator(mode="after")
    def _check(self) -> ReachSpec:
        if len(self.courses_deg) != len(self.speed) or not self.speed:
            raise ValueError("courses_deg and speed need the same, non-zero length")
        if any(b <= a for a, b in zip(self.courses_deg, self.courses_deg[1:], strict=False)):
            raise ValueError("courses_deg must increase strictly")
        if self.courses_deg[0] < 0.0 or self.courses_deg[-1] > 90.0:
            raise ValueError("courses_deg must lie within 0..90 (folded courses)")
        if any(v <= 0 for v in self.speed):
            raise ValueError("speeds must be > 0 m/s")
        return self

    def __call__(self, folded_deg: float) -> float:
        """m/s on the folded course: linear between the courses, held outside them."""
        return PiecewiseLinear(x=self.courses_deg, y=self.speed)(folded_deg)


class CalibrationSpec(Spec):
    """Seed 000's power calibration: P = K * K_l * V ... with factors as piecewise-linear tables.

    ``k`` is PWM counts per m/s of wheel rim speed; the tables are dimensionless factors of power.
    ``motors`` (optional) is the per-motor map applied after them, ``rollers`` (optional) the idle
    wheels' roller drag added on top, ``reach`` (optional) the fastest MOVE per course that lands.
    """

    k: float = Field(gt=0, description="PWM counts per m/s of rim speed")
    k_l: CourseTable | None = None
    k_t: PiecewiseLinear | None = None
    k_r: PiecewiseLinear | None = None
    motors: MotorMapSpec | None = None
    rollers: RollerDragSpec | None = None
    reach: ReachSpec | None = None
    """The calibrated reach (none: the controller knows none and runs every MOVE as asked)."""
    fold_axes_deg: tuple[float, ...] | None = Field(
        default=None,
        min_length=1,
        description="the axes (degrees) K_l's and the reach's courses fold from; absent: the idle axes",
    )
    """Which lookup the K_l and reach courses were made for (:mod:`omnibot.robot.courses`): absent in
    every section written before the marker, whose courses fold from the idle axes; written where a
    robot's course axes are not its idle axes (a mecanum base: ``[0.0]``)."""


def course_axes(wheels: tuple[WheelSpec, ...] | list[WheelSpec]) -> list[float]:
    """The axes (degrees) K_l's and the reach's courses fold from on a robot with these wheels."""
    return fold_axes.course_axes([w.traction_angle for w in wheels], [w.gamma_deg for w in wheels])


def calibration_for(
    spec: CalibrationSpec, wheels: tuple[WheelSpec, ...] | list[WheelSpec]
) -> CalibrationSpec:
    """``spec`` with its K_l and reach on the course axes of a robot with these ``wheels``.

    A section made on them is returned as it is (its ``fold_axes_deg`` set where they are not the
    idle axes); one made on other axes (a mecanum section written before the marker: courses from the
    diagonals, 0..45) is moved onto them exactly, or refused (ValueError) when it cannot be."""
    target = course_axes(wheels)
    idle = fold_axes.idle_axes([w.traction_angle for w in wheels])
    source = list(spec.fold_axes_deg) if spec.fold_axes_deg is not None else idle
    marker = None if fold_axes.same_axes(target, idle) else tuple(target)
    if fold_axes.same_axes(source, target):
        return spec if spec.fold_axes_deg == marker else spec.model_copy(update={"fold_axes_deg": marker})
    update: dict[str, Any] = {"fold_axes_deg": marker}
    try:
        if spec.k_l is not None:
            curves = [(c.x, c.y) for c in spec.k_l.curves]
            new, moved = fold_axes.move_curves(spec.k_l.courses_deg, curves, source, target)
            update["k_l"] = CourseTable(
                courses_deg=tuple(new), curves=tuple(PiecewiseLinear(x=x, y=y) for x, y in moved)
            )
        if spec.reach is not None:
            new, speeds = fold_axes.move_reach(spec.reach.courses_deg, spec.reach.speed, source, target)
            update["reach"] = ReachSpec(courses_deg=tuple(new), speed=tuple(speeds))
    except ValueError as exc:
        raise ValueError(
            f"fold_axes_deg: the K_l courses count from the axes {_degrees(source)}, this robot's from "
            f"{_degrees(target)} (docs/calibration.md, Courses), and the tables cannot be moved there "
            f"exactly ({exc}): calibrate the robot again"
        ) from None
    return spec.model_copy(update=update)


def _degrees(axes: list[float]) -> str:
    return "[" + ", ".join(f"{a:g}" for a in axes) + "] degrees"
