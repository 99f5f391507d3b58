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
from typing import Any

from pydantic import Field, ValidationError, ValidationInfo, field_validator, model_validator

from omnibot.config_errors import explain, read_yaml, suggest
from omnibot.errors import ConfigError
from omnibot.robot.calibration_spec import CalibrationSpec, calibration_for
from omnibot.robot.parts import BatterySpec, Footprint, WheelSpec
from omnibot.robot.sensors import EncoderSpec, GyroSpec, ScannerSpec, SonarSpec
from omnibot.robot.spec import Spec

PRESET_DIR = Path(__file__).with_name("presets")


class LimitsSpec(Spec):
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


class ControllerSpec(Spec):
    """Motor-controller settings baked into the firmware for this robot."""

    loop_hz: float = Field(default=500.0, gt=0)
    queue_capacity: int = Field(default=16, ge=1)
    baud: int = Field(default=115200, gt=0)
    line_max: int = Field(default=64, ge=16)
    wheel_speed_control: bool = False
    speed_kp: float = Field(default=0.0, ge=0, description="PWM counts per rad/s of wheel speed error")
    speed_ki: float = Field(default=0.0, ge=0)


class RobotDescription(Spec):
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
