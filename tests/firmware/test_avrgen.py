"""The UNO firmware's generated headers: up to date, and faithful to the Python definitions."""

from __future__ import annotations

import re

import pytest

from omnibot.firmware import avrboard, avrfeatures, avrgen, speedctl
from omnibot.firmware.config import build_config
from omnibot.protocol import codes
from omnibot.robot import load_robot


def test_checked_in_headers_are_up_to_date() -> None:
    for path, text in avrgen.generated_files().items():
        assert path.exists(), f"{path} is missing: run `python -m omnibot.firmware.avrgen`"
        assert path.read_text(encoding="utf-8") == text, (
            f"{path.name} is stale: run `python -m omnibot.firmware.avrgen` and commit the result"
        )


def _define(text: str, name: str) -> str:
    m = re.search(rf"^#define {name} (.+)$", text, re.MULTILINE)
    assert m, name
    return m.group(1)


@pytest.mark.parametrize("robot", avrgen.ROBOTS)
def test_header_carries_codes_limits_and_kinematics(robot: str) -> None:
    text = avrgen.header_source(robot)
    cfg = build_config(load_robot(robot))
    for code, message in codes.TEXTS.items():
        if code in avrgen.NOT_SENT:  # the UNO never sends it: its text would only take flash
            name = next(k for k, v in vars(codes).items() if k.startswith("W_") and v == code)
            assert f"TEXT_{code}[]" not in text and _define(text, f"P_{name}") == str(code)
        else:
            assert f'TEXT_{code}[] PROGMEM = "{message}";' in text
    for name, kid in codes.COMMANDS.items():
        assert _define(text, f"K_{name}") == str(kid)
    assert _define(text, "ROBOT_NAME") == f'"{robot}"'
    assert int(_define(text, "V_MAX")) == int(cfg["speed_max_cms"])
    shift = int(_define(text, "RIM_SHIFT"))
    rows = re.search(r"RIM_Q\[MOTORS\]\[3\] PROGMEM = \{\n(.*?)\n\};", text, re.DOTALL)
    assert rows
    fixed = [[int(v) for v in row.strip(" {},").split(", ")] for row in rows.group(1).splitlines()]
    for row_q, row in zip(fixed, cfg["rim"], strict=True):
        for q, v in zip(row_q, row, strict=True):
            assert abs(q / (1 << shift) - v) <= 0.5 / (1 << shift)
            assert -32768 <= q <= 32767
    assert int(_define(text, "DEFAULT_K")) == round(cfg["k"] * 10)


def test_limits_round_to_the_same_integer_checks() -> None:
    text = avrgen.header_source("omni4")
    # rate_max_dps 899.54: an integer F is out when abs(F) >= 900, as abs(F) >= 899.54 in Python
    assert _define(text, "F_MAX_EXCL") == "900"
    assert _define(text, "V_MIN") == "30" and _define(text, "L_CLAMP") == "499"


@pytest.mark.parametrize("robot", avrgen.ROBOTS)
def test_the_uno_takes_vel_without_its_acceleration(robot: str) -> None:
    """The UNO speaks protocol version 2 only (docs/uno.md): its keyword table gives VEL four
    parameters, so a VEL with A gets ERROR 24 instead of being half read."""
    text = avrgen.header_source(robot)
    assert '{"VEL", 6, 4, 4, 0},' in text
    assert _define(text, "P_PROTOCOL_VERSION") == "2"


def test_the_mega_header_differs_from_the_unos_only_in_its_pin_map_and_features() -> None:
    uno, mega = avrgen.header_source("omni4"), avrgen.header_source("omni4", "mega")
    cut = "pin map (docs/uno.md) ---- */"
    assert uno.split(cut)[0].replace("Arduino UNO", "") == mega.split(cut)[0].replace("Arduino Mega 2560", "")
    # the Mega's pins: D9 (OC2B, PH6) for motor 1, the encoders on PB0..PB3 (PCINT0..3), echo ICP5 (D48)
    assert _define(mega, "M0_PWM_PORT") == "PORTH" and _define(mega, "M0_PWM_BIT") == "6"
    assert [_define(mega, f"M{i}_ENC_PCINT") for i in range(4)] == ["0", "1", "2", "3"]
    assert _define(mega, "SONAR_TRIG_PORT") == "PORTL" and _define(mega, "SONAR_TRIG_BIT") == "2"
    assert "mcu atmega2560" in avrboard.board_source("omni4", "mega")
    assert "mcu" not in avrboard.board_source("omni4")  # the harness's default chip


def _floats(text: str, name: str) -> list[float]:
    m = re.search(rf"{name}\[.*?PROGMEM = \{{(.*?)\}};", text)
    assert m, name
    return [float(v.strip(" {}f")) for v in m.group(1).split(",")]


@pytest.mark.parametrize("robot", avrgen.ROBOTS)
def test_the_mega_header_switches_on_what_the_unos_flash_cannot_hold(robot: str) -> None:
    """Versions 3 and 4's VEL acceleration, the MOVE progress check, the calibrated reach, braking to
    rest, the closed-loop landing, speedctl.py's loop: 1 on the Mega with the config's tables and
    gains and the two codes' texts, absent on the UNO (features.h: 0)."""
    uno, mega = avrgen.header_source(robot), avrgen.header_source(robot, "mega")
    assert "FEATURE_" not in uno and "TEXT_17" not in uno and "TEXT_18" not in uno
    for name in (
        "FEATURE_VEL_ACCEL",
        "FEATURE_PROGRESS",
        "FEATURE_REACH",
        "FEATURE_BRAKE",
        "FEATURE_LANDING",
        "FEATURE_SPEEDCTL",
    ):
        assert _define(mega, name) == "1"
    assert _define(mega, "P_VERSION_MAX") == str(codes.VERSIONS[-1])
    assert _define(mega, "P_VEL_PARAMS_MAX") == str(codes.VEL_PARAMS_MAX)
    for code in avrfeatures.FEATURE_TEXTS:
        assert f'TEXT_{code}[] PROGMEM = "{codes.TEXTS[code]}";' in mega
    cfg = build_config(load_robot(robot))
    assert _floats(mega, "ACCEL_BODY_FF") == pytest.approx([v for row in cfg["body_ff"] for v in row])
    wheel = [cfg["wheel_ff"][i] * j for i, row in enumerate(cfg["J"]) for j in row]
    assert _floats(mega, "ACCEL_WHEEL_FF") == pytest.approx(wheel)
    assert _floats(mega, "TRAVEL") == pytest.approx([v for row in cfg["travel"] for v in row])
    assert float(_define(mega, "PROGRESS_TOLERANCE").rstrip("f")) == cfg["progress_tolerance"]
    assert _define(mega, "DEFAULT_REACH_N") == str(len(cfg["reach"][0]))
    assert _floats(mega, "TURN") == pytest.approx(cfg["turn"])
    assert _floats(mega, "CREEP_MIX") == pytest.approx([v for row in cfg["creep_mix"] for v in row])
    assert float(_define(mega, "LAND_ACCEL").rstrip("f")) == cfg["land_accel"][0]
    assert _define(mega, "STEADY_PERIODS") == str(speedctl.STEADY_PERIODS)
    steady = float(_define(mega, "SPEED_STEADY").rstrip("f"))
    assert steady == pytest.approx(cfg["speed_ki_steady"] / cfg["speed_ki"]) and steady > 1.0
