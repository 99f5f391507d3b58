"""config.py: the plain config dict, robot_config.py and the board file set."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

from omnibot.firmware import config as fwconfig
from omnibot.robot.description import load_robot, preset_names


@pytest.mark.parametrize("name", preset_names())
def test_config_is_plain_literals_and_round_trips(name: str) -> None:
    cfg = fwconfig.build_config(load_robot(name))
    src = fwconfig.config_module_source(cfg)
    tree = ast.parse(src)
    value = ast.literal_eval(tree.body[-1].value)  # type: ignore[attr-defined]
    assert value == cfg
    assert cfg["motors"] == len(cfg["rim"]) == len(cfg["J"]) == len(cfg["encoder_cpr"])


def test_omni4_limits_in_protocol_units() -> None:
    robot = load_robot("omni4")
    cfg = fwconfig.build_config(robot)
    assert cfg["distance_max_cm"] == 500.0
    assert (cfg["speed_min_cms"], cfg["speed_max_cms"]) == (30.0, 100.0)
    assert cfg["curvature_max"] == 100.0
    assert 899 < cfg["rate_max_dps"] < 900
    assert robot.calibration is not None and robot.calibration.k_r is not None
    assert cfg["k"] == robot.calibration.k
    assert cfg["kr"] == [list(robot.calibration.k_r.x), list(robot.calibration.k_r.y)]
    assert cfg["sonar_period_min_ms"] == [60]
    assert cfg["encoder_cpr"] == [440] * 4
    assert cfg["pwm_max"] == 255 and cfg["power_min"] == 0
    assert cfg["rim"][0] == pytest.approx([0.0, 1.0, 0.096])


def test_stage_board_and_cli(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert fwconfig.main(["omni3", str(tmp_path)]) == 0
    files = {p.relative_to(tmp_path).as_posix() for p in tmp_path.rglob("*.py")}
    assert {
        "main.py",
        "robot_config.py",
        "omnibot/protocol/codes.py",
        "omnibot/firmware/controller.py",
    } <= files
    assert "omnibot/firmware/config.py" not in files
    assert "mpremote" in capsys.readouterr().out
    assert fwconfig.main(["omni4", "--print"]) == 0
    assert "CONFIG = {" in capsys.readouterr().out
