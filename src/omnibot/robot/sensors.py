"""The sensors in a robot description: motor encoders, tracking wheels, gyro, sonars and the laser
scanner."""

from __future__ import annotations

import math
from typing import Literal

from pydantic import Field, model_validator

from omnibot.robot.spec import Spec


class MotorEncoderSpec(Spec):
    """Quadrature encoder on a driven wheel's motor."""

    wheel: str
    counts_per_rev: int = Field(gt=0, description="quadrature counts per wheel revolution")


class TrackingWheelSpec(Spec):
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


class EncoderSpec(Spec):
    """The robot's encoders: on the driven wheels' motors and on passive tracking wheels."""

    motors: tuple[MotorEncoderSpec, ...] = ()
    tracking: tuple[TrackingWheelSpec, ...] = ()


class GyroSpec(Spec):
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


class SonarSpec(Spec):
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


class ScannerSpec(Spec):
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
