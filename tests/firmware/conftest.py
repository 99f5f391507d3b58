"""Fixtures: the omni4 firmware on a FakeHAL with scripted time.

The rig's calibration is pinned to seed 000's plain form, K = 220 PWM counts per m/s and flat
factors (``FORMULA_CALIBRATION``), so these tests check the formulas with numbers they can state, whatever
the presets' fitted tables are.
"""

from __future__ import annotations

from typing import Any

import pytest

from omnibot.firmware.config import build_config
from omnibot.firmware.controller import Controller
from omnibot.robot import CalibrationSpec, load_robot
from tests.firmware.fakehal import FakeHAL, advance


class Rig:
    """A controller, its FakeHAL and helpers to talk to it."""

    def __init__(self, config: dict[str, Any]) -> None:
        self.config = config
        self.hal = FakeHAL(
            config["motors"], len(config["sonar_period_min_ms"]), gyro=0 if config["gyro"] else None
        )
        self.ctrl = Controller(self.hal, config)
        self.hello = self.hal.lines()

    def send(self, text: str) -> list[str]:
        """Send text (terminator included by the caller), poll once, return the lines written."""
        self.hal.send(text)
        self.ctrl.poll()
        return self.hal.lines()

    def cmd(self, text: str) -> list[str]:
        return self.send(text + "\n")

    def run(self, ms: int, step_us: int = 1000) -> list[str]:
        advance(self.ctrl, self.hal, ms, step_us)
        return self.hal.lines()

    def status(self) -> str:
        (line,) = self.cmd("STATUS")
        return line


FORMULA_CALIBRATION = CalibrationSpec(k=220.0)


def make_rig(robot: str = "omni4", **overrides: Any) -> Rig:
    description = load_robot(robot).model_copy(update={"calibration": FORMULA_CALIBRATION})
    config = build_config(description)
    config.update(overrides)
    return Rig(config)


@pytest.fixture
def rig() -> Rig:
    return make_rig()
