"""The Arduino boards' pin maps: a wiring checked against its board's pins and timers."""

from __future__ import annotations

import pytest

from omnibot.errors import ConfigError
from omnibot.firmware import avrboard, avrgen


def test_unknown_pin_is_a_config_error() -> None:
    with pytest.raises(ConfigError, match="not an Arduino UNO pin"):
        avrboard.pin("D14")


def test_mega_pins_are_checked_against_the_megas_own_map(monkeypatch: pytest.MonkeyPatch) -> None:
    assert avrboard.pin("D53", avrboard.board("mega")) == ("B", 0)
    with pytest.raises(ConfigError, match="not an Arduino Mega 2560 pin"):
        avrboard.pin("D54", avrboard.board("mega"))
    with pytest.raises(ConfigError, match="no board 'due'"):
        avrboard.board("due")
    wiring = {**avrboard.MEGA_WIRING["omni4"], "sonar_echo": "D8"}
    monkeypatch.setitem(avrboard.MEGA_WIRING, "omni4", wiring)
    with pytest.raises(ConfigError, match="echo must be on D48"):
        avrgen.header_source("omni4", "mega")
    monkeypatch.setitem(
        avrboard.MEGA_WIRING, "omni4", {**wiring, "sonar_echo": "D48", "pwm": ["D2", "D4", "D13", "D10"]}
    )
    with pytest.raises(ConfigError, match="D2 is not a PWM pin of timers 0 and 2"):
        avrgen.header_source("omni4", "mega")
