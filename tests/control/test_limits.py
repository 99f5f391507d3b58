"""The limits a speed profile keeps within: their checks and scaling."""

from __future__ import annotations

import pytest

from omnibot.control.paths import MotionLimits
from tests.control.test_profile import LIM


def test_limits_validation_and_scaling() -> None:
    with pytest.raises(ValueError, match="v_max"):
        MotionLimits(0.0, 1.0, 1.0, 1.0)
    scaled = LIM.scaled(0.5)
    assert (scaled.a_max, scaled.alpha_max, scaled.v_max) == (1.0, 10.0, 0.5)
    assert LIM.with_turn_rate(3.0).w_max == 3.0
