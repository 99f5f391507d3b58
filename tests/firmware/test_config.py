"""config.py: the plain config dict, robot_config.py and the board file set."""

from __future__ import annotations

import ast
import math
from pathlib import Path
from typing import Any

import pytest

from omnibot.errors import ConfigError
from omnibot.firmware import config as fwconfig
from omnibot.robot import load_robot, preset_names


@pytest.mark.parametrize("name", preset_names())
def test_config_is_plain_literals_and_round_trips(name: str) -> None:
    cfg = fwconfig.build_config(load_robot(name))
    src = fwconfig.config_module_source(cfg)
    tree = ast.parse(src)
    value = ast.literal_eval(tree.body[-1].value)  # type: ignore[attr-defined]
    assert value == cfg
    assert cfg["motors"] == len(cfg["rim"]) == len(cfg["J"]) == len(cfg["encoder_cpr"])


@pytest.mark.parametrize("name", preset_names())
def test_the_least_squares_keys_are_the_inverse_rounded_with_no_signed_zero(name: str) -> None:
    """travel, turn, creep_mix and body_ff come through the least-squares inverse, whose exact zeros
    are a few rounding errors of either sign: written as 0.0, never -0.0, so the literals do not
    depend on the SVD that computed them."""
    robot = load_robot(name)
    cfg = fwconfig.build_config(robot)
    flat = [v for key in ("travel", "creep_mix", "body_ff") for row in cfg[key] for v in row] + cfg["turn"]
    assert not [v for v in flat if v == 0.0 and math.copysign(1.0, v) < 0]
    cpr = cfg["encoder_cpr"]
    forward = robot.forward_rows
    assert cfg["turn"] == [
        pytest.approx(forward[2][i] * 2 * math.pi / c, abs=1e-12) for i, c in enumerate(cpr)
    ]


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
    # wheel 1 drives along y, so its rollers roll along x; 440 counts per turn over 8 rollers
    assert cfg["roller_dir"][0] == pytest.approx([-1.0, 0.0]) and cfg["roller_pitch"] == [55.0] * 4
    assert cfg["roller_cos"] == cfg["roller_sin"] == [0.0] * 4 and cfg["roller_coast"] == [[0.0], [0.0]]


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


def test_a_limit_that_overflows_in_protocol_units_stages_nothing(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    import yaml

    from omnibot.robot.description import PRESET_DIR

    data = yaml.safe_load((PRESET_DIR / "omni4.yaml").read_text())
    data["limits"]["speed_max"] = 1e307  # finite in m/s, infinite in cm/s
    robot = tmp_path / "fast.yaml"
    robot.write_text(yaml.safe_dump(data))
    board = tmp_path / "board"
    assert fwconfig.main([str(robot), str(board)]) == 2
    err = capsys.readouterr().err
    assert "cannot hold speed_max_cms = inf" in err and "Traceback" not in err
    assert not board.exists()


def _robot_with_gyro(tmp_path: Path, no_sonar: bool = False, **gyro: Any) -> Path:
    import yaml

    from omnibot.robot.description import PRESET_DIR

    data = yaml.safe_load((PRESET_DIR / "omni4.yaml").read_text())
    data["gyro"] = {"model": "MPU6050", **gyro}
    if no_sonar:
        data["sonars"] = []
    path = tmp_path / "robot.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


def test_the_gyro_pins_come_from_the_description(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """omni4's MPU6050 on the defaults: I2C0 on GP1 (SCL) and GP0 (SDA) at 0x68, 400 kHz, FS_SEL 0
    (+-250 deg/s: the description's range and 1/131 deg/s resolution), DLPF_CFG 3 (42 Hz); those pins
    were the UART's, so the protocol goes to USB."""
    pins = fwconfig.build_config(load_robot("omni4"))["pins"]
    assert pins["gyro"] == [0, 1, 0, 0x68, 400000, 0, 3]
    assert pins["uart"] is None
    board = tmp_path / "board"
    assert fwconfig.main(["omni4", str(board)]) == 0
    written = (board / "robot_config.py").read_text()
    assert "'gyro': [0, 1, 0, 104, 400000, 0, 3]" in written and "'gyro': None" not in written
    assert (board / "omnibot" / "firmware" / "mpu6050.py").exists()
    capsys.readouterr()
    robot = load_robot(_robot_with_gyro(tmp_path, i2c_address=0x69, i2c_freq=100000, bandwidth_hz=10))
    assert fwconfig.build_config(robot)["pins"]["gyro"] == [0, 1, 0, 0x69, 100000, 0, 5]
    # on I2C1's GP26 and GP27 (free without the sonar) the UART keeps GP0 and GP1
    robot = load_robot(_robot_with_gyro(tmp_path, no_sonar=True, i2c_bus=1, sda_pin=26, scl_pin=27))
    pins = fwconfig.build_config(robot)["pins"]
    assert pins["gyro"] == [1, 27, 26, 0x68, 400000, 0, 3] and pins["uart"] == [0, 0, 1]


def test_a_robot_without_an_mpu6050_has_no_gyro_pins(tmp_path: Path) -> None:
    import yaml

    data = yaml.safe_load(_robot_with_gyro(tmp_path).read_text())
    data["gyro"] = {"model": "generic"}
    (tmp_path / "generic.yaml").write_text(yaml.safe_dump(data))
    pins = fwconfig.build_config(load_robot(tmp_path / "generic.yaml"))["pins"]
    assert pins["gyro"] is None and pins["uart"] == [0, 0, 1]


@pytest.mark.parametrize(
    ("gyro", "key", "words"),
    [
        ({"sda_pin": 26, "scl_pin": 27}, "gyro.sda_pin", "pin 26 is the board's sonars pin already"),
        ({"sda_pin": 2, "scl_pin": 3}, "gyro.scl_pin", "pin 3 is the board's motors pin already"),
        ({"sda_pin": 27, "scl_pin": 27}, "gyro.scl_pin", "SCL and SDA are both pin 27"),
        ({"range": 50.0}, "gyro.range", "beyond an MPU6050's 2000 deg/s"),
        ({"resolution": 1e-3}, "gyro.resolution", "+-250 deg/s range"),
        ({"i2c_address": 0x6A}, "i2c_address", ""),
    ],
)
def test_bad_gyro_wiring_names_the_key(tmp_path: Path, gyro: dict[str, Any], key: str, words: str) -> None:
    with pytest.raises(ConfigError) as info:
        fwconfig.build_config(load_robot(_robot_with_gyro(tmp_path, **gyro)))
    assert key in str(info.value) and words in str(info.value)
