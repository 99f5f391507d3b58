"""Teleop parameters: seed 003's joystick mapping, its defaults, and a YAML file for other pads.

The keys and defaults are seed 003's ``teleop_node`` and ``joy_node`` parameters (ROS 2
``teleop_twist_joy`` and ``joy``), so a ROS parameter file carries over::

    axis_linear: {x: 3, y: 1}            # pad axis index per body direction
    scale_linear: {x: -3.5, y: 3.5}      # m/s at full deflection
    scale_linear_turbo: {x: -50.0, y: 50.0}
    axis_angular: {yaw: 0}
    scale_angular: {yaw: 3.5}            # rad/s at full deflection
    scale_angular_turbo: {yaw: 50.0}
    enable_button: 7                     # hold to drive (the deadman)
    enable_turbo_button: 6               # hold to drive with the turbo scales (-1: none)
    require_enable_button: true
    deadzone: 0.05                       # joy_node: axis values within it read 0
    autorepeat_rate: 20.0                # Hz: commands are sent (repeated) this often
    device_id: 0                         # joy_node: which pad (0: the first attached)

omnibot adds the safety timing and optional speed caps::

    vel_timeout: 0.25      # s, the controller's VEL watchdog (0.001..1, longer than one period)
    input_timeout: 0.5     # s without fresh input before the robot is stopped
    stop_repeats: 5        # zero-velocity commands sent when driving ends
    speed_max: null        # m/s cap below the robot's limit (null: the robot's)
    angular_speed_max: null

A file may also be a ROS 2 parameter file (``teleop_node: {ros__parameters: {...}}`` and
``joy_node: {ros__parameters: {...}}``, as printed in seed 003); the ``ros__parameters`` of every
node are merged (two nodes giving one key different values is an error). A key given in the file
replaces that key's default whole (``axis_linear: {x: 1}`` drives x only). Unknown keys are errors
that name the key and suggest the right one; so is a key given twice in one mapping, as the seed
prints ``axis_linear`` (:func:`omnibot.config_errors.read_yaml`). :data:`SEED_003_FILE` is seed 003's
file with those pairs merged.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

from pydantic import BaseModel, ConfigDict, Field, ValidationError, model_validator

from omnibot.config_errors import explain, read_yaml
from omnibot.errors import ConfigError

VEL_TIMEOUT_MAX = 1.0
"""s: the longest VEL watchdog the protocol allows."""

SEED_003_FILE = Path(__file__).with_name("seed003.yaml")
"""Seed 003's ROS 2 parameter file, its duplicate keys merged (the defaults, as a file)."""


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class LinearAxes(_Strict):
    """Pad axis index per body direction (absent: not driven). An omnidirectional base has x and y."""

    x: int | None = Field(default=None, ge=0)
    y: int | None = Field(default=None, ge=0)


class LinearScales(_Strict):
    """m/s per unit of axis deflection, per body direction."""

    x: float | None = Field(default=None, allow_inf_nan=False)
    y: float | None = Field(default=None, allow_inf_nan=False)


class AngularAxes(_Strict):
    """Which pad axis turns the robot (None: no axis does)."""

    yaw: int | None = Field(default=None, ge=0)


class AngularScales(_Strict):
    """rad/s per unit of axis deflection."""

    yaw: float | None = Field(default=None, allow_inf_nan=False)


class TeleopConfig(_Strict):
    """The joystick-to-twist parameters; the defaults are seed 003's values."""

    axis_linear: LinearAxes = LinearAxes(x=3, y=1)
    scale_linear: LinearScales = LinearScales(x=-3.5, y=3.5)
    scale_linear_turbo: LinearScales = LinearScales(x=-50.0, y=50.0)
    axis_angular: AngularAxes = AngularAxes(yaw=0)
    scale_angular: AngularScales = AngularScales(yaw=3.5)
    scale_angular_turbo: AngularScales = AngularScales(yaw=50.0)
    enable_button: int = Field(default=7, ge=0)
    enable_turbo_button: int | None = Field(default=6, ge=-1)
    require_enable_button: bool = True
    deadzone: float = Field(default=0.05, ge=0.0, lt=1.0)
    autorepeat_rate: float = Field(default=20.0, gt=0.0, le=200.0, allow_inf_nan=False)
    device_id: int = Field(default=0, ge=0)
    vel_timeout: float = Field(default=0.25, gt=0.0, le=VEL_TIMEOUT_MAX)
    input_timeout: float = Field(default=0.5, gt=0.0, allow_inf_nan=False)
    stop_repeats: int = Field(default=5, ge=1, le=100)
    speed_max: float | None = Field(default=None, gt=0.0, allow_inf_nan=False)
    angular_speed_max: float | None = Field(default=None, gt=0.0, allow_inf_nan=False)

    @model_validator(mode="after")
    def _check(self) -> TeleopConfig:
        for axes, scales in (("axis_linear", "scale_linear"), ("axis_angular", "scale_angular")):
            for direction, index in getattr(self, axes):
                if index is not None and getattr(getattr(self, scales), direction) is None:
                    raise ValueError(f"{axes}.{direction} is mapped but {scales}.{direction} is missing")
        if self.vel_timeout <= self.period:
            raise ValueError(
                f"vel_timeout {self.vel_timeout:g} s must be longer than the command period "
                f"{self.period:g} s (autorepeat_rate {self.autorepeat_rate:g} Hz), else the watchdog "
                "stops the robot between commands"
            )
        if self.input_timeout < self.period:
            raise ValueError(
                f"input_timeout {self.input_timeout:g} s must be at least the command period {self.period:g} s"
            )
        return self

    @property
    def period(self) -> float:
        """s between commands: 1 / autorepeat_rate."""
        return 1.0 / self.autorepeat_rate

    @property
    def turbo_button(self) -> int | None:
        """The turbo button's index, None if there is none (-1 or null in the file)."""
        b = self.enable_turbo_button
        return None if b is None or b < 0 else b


def _flatten_ros(data: Mapping[str, Any], source: str) -> dict[str, Any]:
    """Merge the ``ros__parameters`` of every node of a ROS 2 parameter file (ConfigError for a key
    two nodes give different values); other files unchanged."""
    nodes = {k: v for k, v in data.items() if isinstance(v, Mapping) and "ros__parameters" in v}
    if not nodes:
        return dict(data)
    merged: dict[str, Any] = {}
    given_by: dict[str, str] = {}
    for name, node in nodes.items():
        params = node["ros__parameters"]
        if not isinstance(params, Mapping):
            continue
        for key, value in params.items():
            if key in merged and merged[key] != value:
                where = f" {source}" if source else ""
                raise ConfigError(
                    f"invalid teleop config{where}: {key}: given by {given_by[key]} ({merged[key]!r}) "
                    f"and by {name} ({value!r})"
                )
            merged[key] = value
            given_by.setdefault(key, name)
    return merged


def parse_teleop_config(data: Any, source: str = "") -> TeleopConfig:
    """Validate a mapping (parsed YAML; ``None`` for an empty file) into a :class:`TeleopConfig`."""
    if data is None:
        data = {}
    if not isinstance(data, Mapping):
        where = f" {source}" if source else ""
        raise ConfigError(f"a teleop config{where} must be a mapping of keys, got {type(data).__name__}")
    try:
        return TeleopConfig.model_validate(_flatten_ros(data, source))
    except ValidationError as exc:
        error = explain(exc, TeleopConfig, "teleop config", source)
        # the cross-key checks name their keys themselves
        raise ConfigError(str(error).replace("(top level): ", "")) from None


def load_teleop_config(path: str | Path | None) -> TeleopConfig:
    """Read a teleop YAML file; ``None`` gives seed 003's defaults."""
    if path is None:
        return TeleopConfig()
    return parse_teleop_config(read_yaml(path, "teleop config"), str(path))
