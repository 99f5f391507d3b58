"""Teleop config: seed 003's defaults, YAML files (plain and ROS 2 parameter files), clear errors."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
import yaml

from omnibot.errors import ConfigError
from omnibot.teleop.config import TeleopConfig, load_teleop_config, parse_teleop_config

SEED_003 = """\
joy_node:
  ros__parameters:
    device_id: 0
    deadzone: 0.05
    autorepeat_rate: 20.0

teleop_node:
  ros__parameters:
    axis_linear: {x: 3, y: 1}
    scale_linear: {x: -3.5, y: 3.5}
    scale_linear_turbo: {x: -50.0, y: 50.0}
    axis_angular: {yaw: 0}
    scale_angular: {yaw: 3.5}
    scale_angular_turbo: {yaw: 50.0}
    enable_button: 7
    enable_turbo_button: 6
    require_enable_button: true
"""


def test_defaults_are_seed_003() -> None:
    c = TeleopConfig()
    assert (c.axis_linear.x, c.axis_linear.y, c.axis_angular.yaw) == (3, 1, 0)
    assert (c.scale_linear.x, c.scale_linear.y, c.scale_angular.yaw) == (-3.5, 3.5, 3.5)
    assert (c.scale_linear_turbo.x, c.scale_linear_turbo.y, c.scale_angular_turbo.yaw) == (-50.0, 50.0, 50.0)
    assert (c.enable_button, c.turbo_button, c.require_enable_button) == (7, 6, True)
    assert (c.deadzone, c.autorepeat_rate, c.device_id) == (0.05, 20.0, 0)
    assert c.period == pytest.approx(0.05)


def test_seed_ros_parameter_file_gives_the_defaults(tmp_path: Path) -> None:
    path = tmp_path / "seed003.yaml"
    path.write_text(SEED_003)
    assert load_teleop_config(path) == TeleopConfig()


def test_plain_file_replaces_keys_whole(tmp_path: Path) -> None:
    path = tmp_path / "pad.yaml"
    path.write_text("axis_linear: {x: 1}\nscale_linear: {x: 0.4}\nenable_turbo_button: -1\nspeed_max: 0.3\n")
    c = load_teleop_config(path)
    assert c.axis_linear.x == 1 and c.axis_linear.y is None
    assert c.turbo_button is None
    assert c.speed_max == 0.3
    assert load_teleop_config(None) == TeleopConfig()
    empty = tmp_path / "empty.yaml"
    empty.write_text("")
    assert load_teleop_config(empty) == TeleopConfig()


@pytest.mark.parametrize(
    ("data", "message"),
    [
        ({"axis_liner": {"x": 1}}, "axis_liner: unknown key; did you mean 'axis_linear'?"),
        ({"axis_linear": {"z": 2}}, "axis_linear.z: unknown key; expected one of: x, y"),
        ({"axis_angular": {"yaww": 2}}, "axis_angular.yaww: unknown key; did you mean 'yaw'?"),
        ({"deadzone": 1.5}, "deadzone: Input should be less than 1"),
        ({"autorepeat_rate": 0}, "autorepeat_rate: Input should be greater than 0"),
        ({"enable_button": "seven"}, "enable_button: Input should be a valid integer"),
        ({"scale_linear": {"x": float("nan")}}, "scale_linear.x: Input should be a finite number"),
        ({"vel_timeout": 2.0}, "vel_timeout: Input should be less than or equal to 1"),
        ({"vel_timeout": 0.04}, "vel_timeout 0.04 s must be longer than the command period 0.05 s"),
        ({"input_timeout": 0.01}, "input_timeout 0.01 s must be at least the command period"),
        (
            {"axis_linear": {"x": 1, "y": 2}, "scale_linear": {"x": 1.0}},
            "axis_linear.y is mapped but scale_linear.y is missing",
        ),
    ],
)
def test_bad_keys_and_values_are_named(data: dict[str, object], message: str) -> None:
    with pytest.raises(ConfigError, match=r"invalid teleop config pad\.yaml") as info:
        parse_teleop_config(data, "pad.yaml")
    assert message in str(info.value)
    assert "(top level)" not in str(info.value)


def test_bad_files(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match="cannot read teleop config"):
        load_teleop_config(tmp_path / "missing.yaml")
    bad = tmp_path / "bad.yaml"
    bad.write_text("axis_linear: [1, 2\n")
    with pytest.raises(ConfigError, match="not valid YAML"):
        load_teleop_config(bad)
    bad.write_text("- 1\n- 2\n")
    with pytest.raises(ConfigError, match="must be a mapping of keys, got list"):
        load_teleop_config(bad)


def test_the_docs_examples_parse() -> None:
    doc = Path(__file__).resolve().parents[2] / "docs" / "teleop.md"
    blocks = re.findall(r"```yaml\n(.*?)```", doc.read_text(), re.S)
    assert blocks
    for block in blocks:
        parse_teleop_config(yaml.safe_load(block), "docs/teleop.md")
