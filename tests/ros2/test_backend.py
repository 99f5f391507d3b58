"""The backend's choice (``--ros-backend``) and the bridge's options as parameters (no DDS)."""

from __future__ import annotations

from types import SimpleNamespace

import pytest

from omnibot.errors import ConfigError
from omnibot.ros2 import backend
from omnibot.ros2.backend import Parameter, choose


def test_auto_is_rclpy_where_it_imports(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(backend, "rclpy_importable", lambda: True)
    assert choose("auto") == "rclpy"
    monkeypatch.setattr(backend, "rclpy_importable", lambda: False)
    assert choose("auto") == "dds"
    assert choose("dds") == "dds"


def test_rclpy_asked_for_where_it_cannot_be_imported_is_one_line(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(backend, "rclpy_importable", lambda: False)
    with pytest.raises(ConfigError, match="rclpy cannot be imported here"):
        choose("rclpy")


def test_an_unknown_backend_is_named() -> None:
    with pytest.raises(ConfigError, match="not 'zenoh'"):
        choose("zenoh")


def test_a_parameter_without_check_is_read_only() -> None:
    assert Parameter("robot", "omni4", "the robot").read_only
    assert not Parameter("cmd_vel_timeout", 0.5, "s", lambda value: None).read_only


def test_the_bridges_parameters_check_then_set_the_cmd_vel_timeout() -> None:
    from omnibot.ros2.assembly import RobotSpec, parameters

    source = SimpleNamespace(timeout=0.5, forced=None)
    made = parameters(
        SimpleNamespace(name="omni4"),
        SimpleNamespace(period=0.02),
        RobotSpec(None, "r1", "r1/"),
        source,
        "dds",
    )
    by_name = {p.name: p for p in made}
    assert {k: p.value for k, p in by_name.items()} == {
        "robot": "omni4",
        "frame_prefix": "r1/",
        "twist_only": False,
        "cycle_period": 0.02,
        "ros_backend": "dds",
        "cmd_vel_timeout": 0.5,
    }
    assert [p.name for p in made if not p.read_only] == ["cmd_vel_timeout"]
    timeout = by_name["cmd_vel_timeout"]
    assert timeout.check is not None
    assert timeout.check(0.8) is None and timeout.check(2) is None
    assert timeout.check(-1.0) == "expected a positive number of seconds, got -1.0"
    assert timeout.check(float("nan")) is not None and timeout.check("1") is not None
    assert timeout.check(True) is not None
    assert source.timeout == 0.5  # checking sets nothing
    timeout.assign(0.8)
    assert source.timeout == 0.8
