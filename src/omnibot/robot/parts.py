"""The body's parts in a robot description: footprint, motors, rollers, wheels (either geometry form)
and the battery."""

from __future__ import annotations

import math
from typing import Literal

from pydantic import Field, model_validator

from omnibot.robot.battery import CHEMISTRIES
from omnibot.robot.spec import Spec


class Footprint(Spec):
    """Plan-view outline of the body, centred on the body frame origin."""

    shape: Literal["circle", "box", "polygon"]
    radius: float | None = Field(default=None, gt=0)
    length: float | None = Field(default=None, gt=0)
    width: float | None = Field(default=None, gt=0)
    points: tuple[tuple[float, float], ...] | None = None
    height: float = Field(default=0.1, gt=0)

    @model_validator(mode="after")
    def _check_shape(self) -> Footprint:
        need = {"circle": ("radius",), "box": ("length", "width"), "polygon": ("points",)}[self.shape]
        for key in need:
            if getattr(self, key) is None:
                raise ValueError(f"a {self.shape} footprint needs '{key}'")
        if self.shape == "polygon" and self.points is not None and len(self.points) < 3:
            raise ValueError("a polygon footprint needs at least 3 points")
        return self

    def outline(self, segments: int = 24) -> list[tuple[float, float]]:
        """Polygon approximating the footprint, counter-clockwise, in the body frame (m)."""
        if self.shape == "circle":
            assert self.radius is not None
            return [
                (
                    self.radius * math.cos(2 * math.pi * k / segments),
                    self.radius * math.sin(2 * math.pi * k / segments),
                )
                for k in range(segments)
            ]
        if self.shape == "box":
            assert self.length is not None and self.width is not None
            hx, hy = self.length / 2, self.width / 2
            return [(hx, hy), (-hx, hy), (-hx, -hy), (hx, -hy)]
        assert self.points is not None
        return list(self.points)

    @property
    def bounding_radius(self) -> float:
        """Radius of the smallest origin-centred circle holding the footprint (m)."""
        return max(math.hypot(x, y) for x, y in self.outline())


class MotorSpec(Spec):
    """A brushed DC gear motor and its driver channel; torques and speeds at the motor shaft."""

    resistance: float = Field(gt=0, description="terminal resistance, ohm")
    torque_constant: float = Field(gt=0, description="N m/A, equal to the back-EMF constant in V s/rad")
    gear_ratio: float = Field(gt=0, description="motor turns per wheel turn")
    gear_efficiency: float = Field(default=0.9, gt=0, le=1)
    rotor_inertia: float = Field(default=1e-6, ge=0, description="kg m^2 at the motor shaft")
    friction_static: float = Field(default=0.0, ge=0, description="Coulomb friction torque at the wheel, N m")
    friction_viscous: float = Field(default=0.0, ge=0, description="viscous friction at the wheel, N m s/rad")
    current_limit: float | None = Field(
        default=None, gt=0, description="driver current limit, A (none: no limit)"
    )
    driver_drop: float = Field(default=0.0, ge=0, description="voltage lost in the driver (L298: about 2 V)")
    deadband: int = Field(default=0, ge=0, description="PWM counts below which the driver gives no output")
    pwm_bits: int = Field(default=8, ge=1, le=16)

    @property
    def current_max(self) -> float:
        """The driver's current limit, A (infinite when it has none)."""
        return math.inf if self.current_limit is None else self.current_limit

    @property
    def pwm_max(self) -> int:
        """Largest PWM command (255 for 8 bits)."""
        return (1 << self.pwm_bits) - 1


class RollerSpec(Spec):
    """The free rollers of an omni or mecanum wheel."""

    count: int = Field(default=8, ge=1, description="rollers around the rim")
    rolling_resistance: float = Field(
        default=0.02, ge=0, description="resistance to rolling along the free direction, fraction of load"
    )
    friction_variation: float = Field(
        default=0.0, ge=0, description="peak relative rise of that resistance with wheel angle (1.0 = 2x)"
    )
    grip: float = Field(
        default=1.0, gt=0, description="roller material's floor friction relative to soft rubber (scales mu)"
    )
    combined_drag: float = Field(
        default=0.0,
        ge=0,
        description="viscous loss while the wheel drives and its rollers roll at once, "
        "fraction of load per m/s at 45 degrees (docs/simulator.md)",
    )


class WheelSpec(Spec):
    """One driven wheel: geometry (either form), rollers and its motor."""

    name: str
    radius: float = Field(gt=0)
    gamma_deg: float = 0.0
    x: float | None = None
    y: float | None = None
    drive_angle_deg: float | None = None
    alpha_deg: float | None = None
    beta_deg: float | None = None
    L: float | None = Field(default=None, gt=0)
    width: float = Field(default=0.02, gt=0)
    inertia: float = Field(default=1e-5, ge=0, description="wheel inertia about its axle, kg m^2")
    rollers: RollerSpec = RollerSpec()
    motor: MotorSpec

    @model_validator(mode="after")
    def _check_form(self) -> WheelSpec:
        cartesian = [k for k in ("x", "y", "drive_angle_deg") if getattr(self, k) is not None]
        polar = [k for k in ("alpha_deg", "beta_deg", "L") if getattr(self, k) is not None]
        if cartesian and polar:
            raise ValueError("give either x/y/drive_angle_deg or alpha_deg/beta_deg/L, not both")
        if not polar and len(cartesian) != 3:
            missing = sorted({"x", "y", "drive_angle_deg"} - set(cartesian))
            raise ValueError(f"wheel geometry needs {', '.join(missing)} (or alpha_deg/beta_deg/L)")
        if polar and len(polar) != 3:
            missing = sorted({"alpha_deg", "beta_deg", "L"} - set(polar))
            raise ValueError(f"seed 003 wheel geometry needs {', '.join(missing)}")
        if abs(math.cos(math.radians(self.gamma_deg))) < 1e-6:
            raise ValueError(
                "gamma_deg of +-90 makes the rollers take the whole drive: the wheel cannot push"
            )
        return self

    @property
    def position(self) -> tuple[float, float]:
        """Contact centre (x, y) in the body frame, m."""
        if self.L is not None:
            assert self.alpha_deg is not None
            a = math.radians(self.alpha_deg)
            return (self.L * math.cos(a), self.L * math.sin(a))
        assert self.x is not None and self.y is not None
        return (self.x, self.y)

    @property
    def drive_angle(self) -> float:
        """Direction in which a positive wheel speed carries the robot at this wheel, rad, body frame."""
        if self.L is not None:
            assert self.alpha_deg is not None and self.beta_deg is not None
            return math.radians(self.alpha_deg + self.beta_deg - 90.0)
        assert self.drive_angle_deg is not None
        return math.radians(self.drive_angle_deg)

    @property
    def gamma(self) -> float:
        """Roller angle, rad."""
        return math.radians(self.gamma_deg)

    @property
    def traction_angle(self) -> float:
        """Direction in which the wheel can push the floor (drive direction turned by gamma), rad."""
        return self.drive_angle + self.gamma


class BatterySpec(Spec):
    """The battery: nominal voltage (V), internal resistance (ohm), capacity (Ah) and the firmware's
    low-voltage thresholds (volts per cell; defaults from the chemistry, robot/battery.py), each
    crossed when the firmware's reading, low-pass filtered over ``filter_s``, stays below it ``delay`` s.

    Below ``warn`` the firmware sends WARN 19, below ``limit`` it scales the motors' power down to
    ``limit_power`` of full (WARN 20), and below ``stop`` it stops the motors and latches (WARN 43, motion refused with ERROR 44) until
    STOP finds the voltage back above ``stop + hysteresis`` (docs/safety.md#battery)."""

    voltage: float = Field(gt=0, description="nominal voltage, V")
    internal_resistance: float = Field(default=0.05, ge=0, description="ohm")
    capacity_ah: float = Field(default=2.0, gt=0)
    chemistry: Literal["lipo", "liion", "life", "nimh"] = "lipo"
    cells: int | None = Field(
        default=None, ge=1, description="cells in series; default voltage / nominal cell"
    )
    warn: float | None = Field(default=None, gt=0, description="V per cell")
    limit: float | None = Field(default=None, gt=0, description="V per cell")
    stop: float | None = Field(default=None, gt=0, description="V per cell")
    hysteresis: float | None = Field(default=None, ge=0, description="V per cell")
    filter_s: float = Field(
        default=1.0, gt=0, description="time constant of the reading's low-pass filter, s"
    )
    delay: float = Field(default=3.0, ge=0, description="s the filtered reading stays below a threshold")
    limit_power: float = Field(default=0.5, gt=0, le=1, description="share of full power below limit")
    charge: float | None = Field(
        default=None,
        ge=0,
        le=1,
        description="simulator: state of charge at start (None: an ideal battery held at its nominal voltage)",
    )

    @model_validator(mode="after")
    def _check_thresholds(self) -> BatterySpec:
        if not self.warn_v > self.limit_v > self.stop_v:
            raise ValueError("battery thresholds must fall: warn > limit > stop")
        return self

    @property
    def n_cells(self) -> int:
        """Cells in series (given, or the nominal voltage over the chemistry's nominal cell)."""
        if self.cells is not None:
            return self.cells
        return max(1, round(self.voltage / CHEMISTRIES[self.chemistry].nominal))

    def _per_cell(self, value: float | None, default: float) -> float:
        return self.n_cells * (default if value is None else value)

    @property
    def warn_v(self) -> float:
        """Pack voltage below which the firmware warns (WARN 19), V."""
        return self._per_cell(self.warn, CHEMISTRIES[self.chemistry].warn)

    @property
    def limit_v(self) -> float:
        """Pack voltage below which the firmware limits power (WARN 20), V."""
        return self._per_cell(self.limit, CHEMISTRIES[self.chemistry].limit)

    @property
    def stop_v(self) -> float:
        """Pack voltage below which the firmware stops and latches (WARN 43), V."""
        return self._per_cell(self.stop, CHEMISTRIES[self.chemistry].stop)

    @property
    def hysteresis_v(self) -> float:
        """How far above a threshold the reading must come back to clear it, V."""
        return self._per_cell(self.hysteresis, CHEMISTRIES[self.chemistry].hysteresis)
