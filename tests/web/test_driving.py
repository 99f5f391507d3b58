"""Driving from the page (web/driving.py): its input as teleop samples, the state frame's drive."""

from __future__ import annotations

import math

import pytest

from omnibot.motion import Twist
from omnibot.runtime import Cycle, Decision
from omnibot.teleop import TeleopConfig, TwistLimits
from omnibot.web.driving import DRIVE_RATE_MAX, drive_limits, drive_state, page_sample
from omnibot.web.messages import Drive


def test_the_pages_full_turn_is_at_most_half_a_turn_a_second() -> None:
    assert drive_limits(TwistLimits(1.2, 9.0)) == TwistLimits(1.2, DRIVE_RATE_MAX)
    assert drive_limits(TwistLimits(0.5, 2.0)) == TwistLimits(0.5, 2.0)


def test_a_drive_is_a_fraction_of_the_pages_full_scale_and_names_its_input() -> None:
    limits = TwistLimits(1.0, 4.0)
    drive = drive_limits(limits)
    request = Drive(type="drive", vx=0.5, w=-1.0, enable=False, source="joystick")
    sample, source = page_sample(request, TeleopConfig(), limits, drive, now=3.0)
    assert source == "joystick"
    assert sample.twist.vx == pytest.approx(0.5) and sample.twist.w == pytest.approx(-math.pi)
    assert not sample.enabled and sample.time == 3.0


def test_the_drive_state_says_who_is_in_control_and_the_twists_rounded_to_mm() -> None:
    cycle = Cycle(7, 1.0, 1.0, None, decision=Decision("page", Twist(0.1, 0.0, 0.0), "page (priority 100)"))
    cycle.latched, cycle.latch_reason = True, "sonar"
    state = drive_state(cycle, "driving", "keyboard", Twist(0.12345, -0.0004, 1.0), "released", teach=False)
    assert state == {
        "state": "driving",
        "source": "keyboard",
        "control": "page",
        "reason": "page (priority 100)",
        "latched": True,
        "latch_reason": "sonar",
        "twist": [0.123, -0.0, 1.0],
        "achieved": None,  # no estimate
        "ended": "released",
        "teach": False,
    }
    assert drive_state(cycle, "idle", "", None, None, teach=True)["twist"] is None
