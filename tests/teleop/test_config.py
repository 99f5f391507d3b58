"""Teleop config: seed 003's defaults, YAML files (plain and ROS 2 parameter files), clear errors;
seed 003's file as the seed prints it (duplicate keys: refused) and as omnibot ships it."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
import yaml

from omnibot.config_errors import load_yaml
from omnibot.errors import ConfigError
from omnibot.teleop.config import SEED_003_FILE, TeleopConfig, load_teleop_config, parse_teleop_config

ROOT = Path(__file__).resolve().parents[2]
AS_PRINTED = ROOT / "tests" / "data" / "seed003_teleop_as_printed.yaml"
"""Seed 003's joy and teleop parameters exactly as its section 4.1 prints them (the two code blocks a
page break splits them into), with ``axis_linear``, ``scale_linear`` and ``scale_linear_turbo`` twice."""

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
        parse_teleop_config(load_yaml(block), "docs/teleop.md")


def test_seed_file_as_printed_is_refused_naming_the_key_and_both_lines() -> None:
    with pytest.raises(ConfigError) as info:
        load_teleop_config(AS_PRINTED)
    lines = AS_PRINTED.read_text().splitlines()
    first, again = (i + 1 for i, line in enumerate(lines) if line == "    axis_linear:")
    assert str(info.value) == (
        f"invalid teleop config {AS_PRINTED}: teleop_node.ros__parameters.axis_linear: "
        f"duplicate key on line {again} (first on line {first}), and 2 more duplicate keys"
    )
    assert (first, again) == (11, 18)
    # what it was refused for: read as yaml.safe_load reads it, the last map wins and forward is gone
    lossy = parse_teleop_config(yaml.safe_load(AS_PRINTED.read_text()))
    assert lossy.axis_linear.x is None and lossy.axis_linear.y == 1


class _MergingLoader(yaml.SafeLoader):
    """Reads a key given twice as the seed means it: its two maps merged into one."""

    def construct_mapping(self, node: yaml.MappingNode, deep: bool = False) -> dict[object, object]:
        out: dict[object, object] = {}
        for key_node, value_node in node.value:
            key, value = self.construct_object(key_node, True), self.construct_object(value_node, True)
            before = out.get(key)
            out[key] = {**before, **value} if isinstance(before, dict) and isinstance(value, dict) else value
        return out


def test_shipped_seed_file_is_the_printed_one_with_its_pairs_merged() -> None:
    meant = yaml.load(AS_PRINTED.read_text(), Loader=_MergingLoader)
    assert meant["teleop_node"]["ros__parameters"]["axis_linear"] == {"x": 3, "y": 1}
    # the one other change: the teleop node named as teleop_twist_joy's launch file names it
    meant["teleop_twist_joy_node"] = meant.pop("teleop_node")
    assert load_yaml(SEED_003_FILE.read_text()) == meant
    assert load_teleop_config(SEED_003_FILE) == TeleopConfig()


def test_the_ros2_docs_show_the_shipped_seed_file() -> None:
    doc = (ROOT / "docs" / "ros2.md").read_text()
    section = doc[doc.index("## teleop_twist_joy with seed 003's parameters") :]
    block = re.search(r"```yaml\n(.*?)```", section, re.S)
    assert block is not None
    assert load_yaml(block.group(1)) == load_yaml(SEED_003_FILE.read_text())


def test_a_key_two_nodes_give_different_values_is_refused() -> None:
    ros = {
        "joy_node": {"ros__parameters": {"deadzone": 0.1}},
        "teleop_node": {"ros__parameters": {"deadzone": 0.2}},
    }
    with pytest.raises(ConfigError) as info:
        parse_teleop_config(ros, "pad.yaml")
    assert (
        str(info.value)
        == "invalid teleop config pad.yaml: deadzone: given by joy_node (0.1) and by teleop_node (0.2)"
    )
    ros["teleop_node"]["ros__parameters"]["deadzone"] = 0.1  # the same value twice says the same thing
    assert parse_teleop_config(ros).deadzone == 0.1


def test_duplicate_keys_in_a_plain_file_are_refused(tmp_path: Path) -> None:
    pad = tmp_path / "pad.yaml"
    pad.write_text("enable_button: 5\naxis_linear: {x: 1, y: 0, x: 2}\nenable_button: 4\n")
    with pytest.raises(ConfigError) as info:
        load_teleop_config(pad)
    assert str(info.value) == (
        f"invalid teleop config {pad}: axis_linear.x: duplicate key on line 2 (first on line 2), "
        "and 1 more duplicate key"
    )
    pad.write_text("enable_button: 5\naxis_linear: {x: 1, y: 0}\nenable_button: 4\n")
    with pytest.raises(
        ConfigError, match=r"pad\.yaml: enable_button: duplicate key on line 3 \(first on line 1\)$"
    ):
        load_teleop_config(pad)
