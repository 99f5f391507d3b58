"""The robot description: one validated model that drives kinematics, firmware, simulator and URDF.

A description is a YAML mapping. Lengths are in metres, masses in kilograms, times in seconds and
angles in degrees where the key ends in ``_deg`` (converted to radians by the properties here).
Every mapping rejects keys it does not know, and the error names the key and suggests the nearest
valid one::

    omnibot: wheels[1].radus: unknown key; did you mean 'radius'?

Wheel geometry is accepted in two forms (see docs/robot.md):

* Cartesian: ``x``, ``y`` (wheel contact centre in the body frame), ``drive_angle_deg`` (direction in
  which a positive wheel speed carries the robot at that wheel, body frame) and ``gamma_deg`` (roller
  angle: the rollers' constrained direction is the drive direction turned by gamma);
* seed 003's polar form: ``alpha_deg``, ``beta_deg``, ``gamma_deg`` and ``L`` (Siegwart's Swedish wheel),
  converted with x = L cos(alpha), y = L sin(alpha), drive angle = alpha + beta - 90 degrees.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from functools import cached_property
from pathlib import Path
from typing import Any, Literal

from pydantic import (
    BaseModel,
    ConfigDict,
    Field,
    ValidationError,
    ValidationInfo,
    field_validator,
    model_validator,
)

from omnibot.config_errors import explain, read_yaml, suggest
from omnibot.errors import ConfigError
from omnibot.robot import courses as fold_axes
from omnibot.robot.battery import CHEMISTRIES

PRESET_DIR = Path(__file__).with_name("presets")


class _Spec(BaseModel):
    """Strict, immutable base: unknown keys are errors, and so is every number that is not finite
    (``.inf``, ``.nan``; the error names the key): no limit, gain or length of a robot is infinite,
    and the firmware's config could not even spell one."""

    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)


class Footprint(_Spec):
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


class MotorSpec(_Spec):
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


class RollerSpec(_Spec):
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


class WheelSpec(_Spec):
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


class BatterySpec(_Spec):
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


class MotorEncoderSpec(_Spec):
    """Quadrature encoder on a driven wheel's motor."""

    wheel: str
    counts_per_rev: int = Field(gt=0, description="quadrature counts per wheel revolution")


class TrackingWheelSpec(_Spec):
    """A passive, unpowered measuring wheel with an encoder (seed 002's vertical/horizontal encoders)."""

    name: str
    x: float
    y: float
    direction_deg: float = Field(description="direction it measures, degrees in the body frame")
    radius: float = Field(gt=0)
    counts_per_rev: int = Field(gt=0)

    @property
    def direction(self) -> float:
        """The measuring direction in the body frame, rad."""
        return math.radians(self.direction_deg)


class EncoderSpec(_Spec):
    """The robot's encoders: on the driven wheels' motors and on passive tracking wheels."""

    motors: tuple[MotorEncoderSpec, ...] = ()
    tracking: tuple[TrackingWheelSpec, ...] = ()


class GyroSpec(_Spec):
    """A yaw-rate gyro (MEMS); noise figures per its datasheet."""

    model: str = "generic"
    rate_hz: float = Field(default=1000.0, gt=0)
    noise_density: float = Field(default=8.7e-5, ge=0, description="rad/s/sqrt(Hz)")
    bias_std: float = Field(default=0.01, ge=0, description="turn-on bias spread, rad/s")
    # A logged MPU6050 shows a bias instability of about 0.0012 degree/s (2e-5 rad/s; Allan deviation,
    # robotics.stackexchange question 8860). 2e-5 rad/s/sqrt(s) lets the bias wander ten times that in
    # 100 s, to allow for a robot warming up; 2e-4 (the old default) wandered a hundred times that.
    bias_walk: float = Field(default=2e-5, ge=0, description="bias random walk, rad/s/sqrt(s)")
    scale_error_std: float = Field(default=0.01, ge=0, description="scale factor error spread, fraction")
    range: float = Field(default=4.363, gt=0, description="saturation, rad/s (MPU6050 +-250 deg/s)")
    resolution: float = Field(default=1.332e-4, ge=0, description="rad/s per LSB (MPU6050: 1/131 deg/s)")
    # A board's wiring of an MPU6050 (firmware/mpu6050.py; docs/firmware.md, "The gyro on a board"): the
    # I2C bus and its pins in the generated board config. The defaults are a Raspberry Pi Pico's I2C0 on
    # GP0 (SDA) and GP1 (SCL); the board's protocol then runs on USB, as those pins were its UART's.
    i2c_bus: int = Field(default=0, ge=0, description="the board's I2C peripheral (machine.I2C id)")
    sda_pin: int = Field(default=0, ge=0, description="board pin of SDA")
    scl_pin: int = Field(default=1, ge=0, description="board pin of SCL")
    i2c_address: Literal[0x68, 0x69] = Field(default=0x68, description="0x68 with AD0 low, 0x69 high")
    i2c_freq: int = Field(
        default=400_000, gt=0, le=400_000, description="bus clock, Hz (the chip's fast mode)"
    )
    bandwidth_hz: float = Field(
        default=42.0, gt=0, description="low-pass bandwidth; the DLPF setting passing it"
    )


class SonarSpec(_Spec):
    """An ultrasonic range finder (HC-SR04 figures by default)."""

    name: str
    x: float
    y: float
    angle_deg: float
    cone_deg: float = Field(default=15.0, gt=0, lt=180)
    min_range: float = Field(default=0.02, ge=0)
    max_range: float = Field(default=4.0, gt=0)
    period_min: float = Field(default=0.060, gt=0, description="shortest measuring cycle, s")
    noise_std: float = Field(default=0.003, ge=0, description="range noise, m")
    miss_probability: float = Field(default=0.02, ge=0, le=1)

    @property
    def angle(self) -> float:
        """The sonar's pointing angle in the body frame, rad."""
        return math.radians(self.angle_deg)

    @property
    def cone(self) -> float:
        """The full width of the sonar's cone, rad."""
        return math.radians(self.cone_deg)


# RPLIDAR A1 (A1M8) datasheet figures (Slamtec, "RPLIDAR A1 Introduction and Datasheet", section
# Measurement Performance): distance range 0.15-12 m (white objects), distance resolution < 0.5 mm
# below 1.5 m and < 1 % of the distance over the whole range, angular resolution 1 degree at the
# typical 5.5 Hz scan rate (360 samples per scan), sample frequency 4000 typical / 8000 max, scan rate
# 1-10 Hz; the A2 datasheet states accuracy as 1 % of range up to 3 m (2 % to 5 m, 2.5 % beyond).
# The protocol reports distances in quarter millimetres (distance_q2) and angles clockwise.
RPLIDAR_A1_RANGE = (0.15, 12.0)
RPLIDAR_A1_SAMPLE_RATE_HZ = 8000.0
RPLIDAR_DISTANCE_UNIT = 0.00025
"""m: one count of the RPLIDAR protocol's distance (q2 fixed point of a millimetre)."""


class ScannerSpec(_Spec):
    """A spinning planar laser scanner (Slamtec RPLIDAR A1 figures by default, see the comment above).

    The mount pose is the scanner frame's in the robot's base frame: ``x``, ``y`` (m), ``yaw_deg``,
    and ``z``, the height of the scan plane above the floor (m), which must clear the robot's body.
    One revolution measures ``rays`` ranges evenly spread over 360 degrees, one after the other while
    the head turns (``motion_distortion``: each ray from where the robot is at its own time), turning
    ``spin`` (RPLIDARs turn clockwise seen from above). A range is the true distance plus
    N(0, noise_std + noise_fraction * distance), quantised to ``resolution``; a ray gets no return
    (inf) with probability ``dropout``, or when the return is outside [range_min, range_max].
    """

    model: str = "rplidar-a1"
    frame: str = Field(default="laser", min_length=1, description="name of the scanner frame (URDF link)")
    x: float = 0.0
    y: float = 0.0
    z: float = Field(gt=0, description="height of the scan plane above the floor, m")
    yaw_deg: float = 0.0
    range_min: float = Field(default=RPLIDAR_A1_RANGE[0], ge=0, description="m")
    range_max: float = Field(default=RPLIDAR_A1_RANGE[1], gt=0, description="m")
    rays: int = Field(default=360, ge=3, description="rays per revolution")
    rate_hz: float = Field(default=5.5, gt=0, description="revolutions per second")
    sample_rate_hz: float = Field(
        default=RPLIDAR_A1_SAMPLE_RATE_HZ, gt=0, description="most rays the scanner measures per second"
    )
    noise_std: float = Field(default=0.0, ge=0, description="range noise independent of distance, 1 sigma, m")
    noise_fraction: float = Field(default=0.01, ge=0, description="range noise per m of distance, 1 sigma")
    resolution: float = Field(default=RPLIDAR_DISTANCE_UNIT, ge=0, description="range quantum, m (0: none)")
    dropout: float = Field(
        default=0.01, ge=0, le=1, description="chance a ray has no return (not in the datasheet: a guess)"
    )
    spin: Literal["clockwise", "counterclockwise"] = "clockwise"
    motion_distortion: bool = True

    @model_validator(mode="after")
    def _check(self) -> ScannerSpec:
        if self.range_min >= self.range_max:
            raise ValueError(f"range_min ({self.range_min} m) must be below range_max ({self.range_max} m)")
        need = self.rays * self.rate_hz
        if need > self.sample_rate_hz * (1 + 1e-9):
            raise ValueError(
                f"{self.rays} rays at {self.rate_hz:g} Hz need {need:g} samples/s; "
                f"the {self.model} measures at most {self.sample_rate_hz:g} (sample_rate_hz)"
            )
        return self

    @property
    def yaw(self) -> float:
        """The mount's yaw in the base frame, rad."""
        return math.radians(self.yaw_deg)

    @property
    def period(self) -> float:
        """Seconds per revolution."""
        return 1.0 / self.rate_hz

    @property
    def angle_increment(self) -> float:
        """Angle between consecutive rays in the scanner frame, rad: negative when spinning clockwise."""
        step = 2 * math.pi / self.rays
        return -step if self.spin == "clockwise" else step


class LimitsSpec(_Spec):
    """What the robot may be asked to do; the controller's parameter checks come from here."""

    speed_min: float = Field(default=0.0, ge=0, description="m/s, below it the robot does not start")
    speed_max: float = Field(gt=0, description="m/s")
    angular_speed_max: float = Field(gt=0, description="rad/s")
    curvature_max: float = Field(gt=0, description="1/m")
    acceleration_max: float = Field(gt=0, description="m/s^2")
    angular_acceleration_max: float = Field(gt=0, description="rad/s^2")
    distance_max: float = Field(default=5.0, gt=0, description="longest finite MOVE, m")
    stop_deceleration: float | None = Field(
        default=None,
        gt=0,
        description="m/s^2 the robot surely reaches when the firmware stops it (the sonar stop's braking "
        "distance); default: derived from the wheels' friction, see RobotDescription.stop_deceleration",
    )
    uncovered_speed: float | None = Field(
        default=None,
        gt=0,
        description="m/s: fastest travel where no armed sonar looks (default max(speed_min, 0.25))",
    )


class PiecewiseLinear(_Spec):
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


class CourseTable(_Spec):
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


class MotorMapSpec(_Spec):
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


class RollerDragSpec(_Spec):
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


class ReachSpec(_Spec):
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


class CalibrationSpec(_Spec):
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


class ControllerSpec(_Spec):
    """Motor-controller settings baked into the firmware for this robot."""

    loop_hz: float = Field(default=500.0, gt=0)
    queue_capacity: int = Field(default=16, ge=1)
    baud: int = Field(default=115200, gt=0)
    line_max: int = Field(default=64, ge=16)
    wheel_speed_control: bool = False
    speed_kp: float = Field(default=0.0, ge=0, description="PWM counts per rad/s of wheel speed error")
    speed_ki: float = Field(default=0.0, ge=0)


class RobotDescription(_Spec):
    """Everything omnibot knows about one robot."""

    name: str
    summary: str = ""
    mass: float = Field(gt=0, description="kg")
    yaw_inertia: float = Field(gt=0, description="kg m^2 about the vertical axis through the centre")
    footprint: Footprint
    wheels: tuple[WheelSpec, ...] = Field(min_length=3)
    battery: BatterySpec
    encoders: EncoderSpec = EncoderSpec()
    gyro: GyroSpec | None = None
    sonars: tuple[SonarSpec, ...] = ()
    scanner: ScannerSpec | None = None
    limits: LimitsSpec
    controller: ControllerSpec = ControllerSpec()
    calibration: CalibrationSpec | None = None

    @field_validator("calibration")
    @classmethod
    def _fold_calibration(cls, spec: CalibrationSpec | None, info: ValidationInfo) -> CalibrationSpec | None:
        """The section's K_l and reach on the robot's course axes (moved there when made on others)."""
        wheels = info.data.get("wheels")
        if spec is None or not wheels:
            return spec
        return calibration_for(spec, wheels)

    @model_validator(mode="before")
    @classmethod
    def _merge_motor_defaults(cls, data: Any) -> Any:
        """A top-level ``motor`` gives every wheel's motor; a wheel's own ``motor`` overrides keys of it."""
        if not isinstance(data, Mapping) or "motor" not in data:
            return data
        data = dict(data)
        default = data.pop("motor")
        if not isinstance(default, Mapping):
            raise ValueError("'motor' must be a mapping")
        wheels = data.get("wheels")
        if isinstance(wheels, list | tuple):
            merged = []
            for wheel in wheels:
                if isinstance(wheel, Mapping):
                    own = wheel.get("motor", {})
                    own = own if isinstance(own, Mapping) else {}
                    merged.append({**wheel, "motor": {**default, **own}})
                else:
                    merged.append(wheel)
            data["wheels"] = merged
        return data

    @model_validator(mode="after")
    def _check_references(self) -> RobotDescription:
        names = [w.name for w in self.wheels]
        if len(set(names)) != len(names):
            raise ValueError(f"wheel names must be unique, got {names}")
        for enc in self.encoders.motors:
            if enc.wheel not in names:
                raise ValueError(suggest(f"encoders.motors wheel '{enc.wheel}'", enc.wheel, names))
        if self.scanner is not None:
            self._check_scanner(self.scanner)
        return self

    def _check_scanner(self, scanner: ScannerSpec) -> None:
        """The scan plane clears the body (the scanner must not see its own robot) and the frame name
        is not one the URDF already uses."""
        top = self.body_top
        if scanner.z <= top:
            raise ValueError(
                f"scanner.z: the scan plane at {scanner.z:g} m would cut the robot's own body (its top is at "
                f"{top:g} m: wheel axle height + footprint.height); mount it higher, e.g. z: {top + 0.05:.3g}"
            )
        taken = {"base_footprint", "base_link", "imu_link"}
        taken |= {f"{w.name}_wheel" for w in self.wheels} | {f"sonar_{s.name}" for s in self.sonars}
        taken |= {f"{t.name}_tracking_wheel" for t in self.encoders.tracking}
        if scanner.frame in taken:
            raise ValueError(
                f"scanner.frame '{scanner.frame}' is already a link of the robot; call it 'laser'"
            )

    @property
    def body_top(self) -> float:
        """Height of the top of the body above the floor, m (the URDF's base_link sits at wheel-axle
        height, and the body's box or cylinder rises footprint.height from there)."""
        return max(w.radius for w in self.wheels) + self.footprint.height

    @property
    def n_wheels(self) -> int:
        """The number of driven wheels."""
        return len(self.wheels)

    @property
    def has_wheel_encoders(self) -> bool:
        """True when every driven wheel has a motor encoder (wheel odometry works)."""
        names = {e.wheel for e in self.encoders.motors}
        return all(w.name in names for w in self.wheels)

    @cached_property
    def stop_deceleration(self) -> float:
        """Deceleration (m/s^2) the robot surely reaches with its motors cut, in its worst direction.

        ``limits.stop_deceleration`` when given. Otherwise a lower bound from the description: with
        the drivers off (the motors coast) the floor stops the robot through each wheel's Coulomb
        friction at the axle (``motor.friction_static / radius`` along the wheel's traction
        direction) and its rollers' rolling resistance (``rolling_resistance`` times the wheel's
        static load, across it). Their components against travel in direction c, summed over the
        wheels, divided by the mass, minimised over c in 1 degree steps. Viscous friction, back-EMF
        of a braked motor and the wheels' inertia are left out (they only help or are small), so
        the simulator stops faster than this (omni4: 2.3 m/s^2 derived, 2.8 measured on wood).
        """
        if self.limits.stop_deceleration is not None:
            return self.limits.stop_deceleration
        load = self.mass * 9.81 / self.n_wheels
        terms = []
        for w in self.wheels:
            axle = w.motor.friction_static / w.radius
            roll = w.rollers.rolling_resistance * load
            terms.append((w.traction_angle, axle, roll))
        worst = math.inf
        for k in range(360):
            c = math.radians(k)
            force = sum(a * abs(math.cos(t - c)) + r * abs(math.sin(t - c)) for t, a, r in terms)
            worst = min(worst, force)
        return max(worst / self.mass, 0.05)

    @property
    def uncovered_speed(self) -> float:
        """Fastest travel (m/s) in a direction no armed sonar covers: ``limits.uncovered_speed`` or
        max(speed_min, 0.25) (ISO 10218's reduced speed is 250 mm/s), at most speed_max."""
        lim = self.limits
        speed = lim.uncovered_speed if lim.uncovered_speed is not None else max(lim.speed_min, 0.25)
        return min(speed, lim.speed_max)

    @cached_property
    def inverse_rows(self) -> tuple[tuple[float, float, float], ...]:
        """The inverse-kinematics matrix J as plain rows, one per wheel (rad/s per unit body twist;
        :func:`omnibot.robot.rows.wheel_matrix`, which refuses a layout of rank below 3)."""
        from omnibot.robot.rows import wheel_matrix

        return wheel_matrix(self)

    @cached_property
    def forward_rows(self) -> tuple[tuple[float, ...], ...]:
        """J's least-squares inverse as plain rows (3, n): the body twist per wheel speeds."""
        from omnibot.robot.rows import pseudo_inverse

        return pseudo_inverse(self.inverse_rows)

    @cached_property
    def wheel_matrix(self) -> Any:
        """:attr:`inverse_rows` as a numpy array (:func:`omnibot.robot.kinematics.wheel_matrix`)."""
        from omnibot.robot.kinematics import wheel_matrix

        return wheel_matrix(self)

    def wheel(self, name: str) -> WheelSpec:
        """The wheel called ``name``; ConfigError with the closest names if there is none."""
        for w in self.wheels:
            if w.name == name:
                return w
        raise ConfigError(suggest("no such wheel", name, [w.name for w in self.wheels]))


# --------------------------------------------------------------------------- loading


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


def parse_description(data: Any, source: str = "") -> RobotDescription:
    """Validate a mapping (e.g. parsed YAML) into a :class:`RobotDescription`."""
    if not isinstance(data, Mapping):
        raise ConfigError(
            f"a robot description must be a mapping, got {type(data).__name__} {source}".strip()
        )
    try:
        return RobotDescription.model_validate(data)
    except ValidationError as exc:
        raise explain(
            exc, RobotDescription, "robot description", source, {RobotDescription: ["motor"]}
        ) from None


def load_description(path: str | Path) -> RobotDescription:
    """Read and validate a YAML robot description file."""
    return parse_description(read_yaml(path, "robot description"), str(path))


def preset_names() -> list[str]:
    """Names of the bundled presets."""
    return sorted(p.stem for p in PRESET_DIR.glob("*.yaml"))


def load_robot(name_or_path: str | Path) -> RobotDescription:
    """A preset by name (``omni4``, ``omni3``, ``mecanum4``) or a description file by path."""
    text = str(name_or_path)
    if text in preset_names():
        return load_description(PRESET_DIR / f"{text}.yaml")
    path = Path(text)
    if path.suffix in {".yaml", ".yml"} or path.exists():
        return load_description(path)
    raise ConfigError(suggest(f"unknown robot '{text}'", text, preset_names()))
