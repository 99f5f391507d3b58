"""The calibration section's own tables (its checks through a whole description: test_description)."""

from __future__ import annotations

import pytest

from omnibot.robot.calibration_spec import PiecewiseLinear


def test_piecewise_linear() -> None:
    f = PiecewiseLinear(x=(0, 100, 255), y=(2.0, 1.0, 0.5))
    assert f(-5) == 2.0 and f(50) == pytest.approx(1.5) and f(177.5) == pytest.approx(0.75) and f(999) == 0.5
    with pytest.raises(ValueError, match="increase strictly"):
        PiecewiseLinear(x=(0, 0), y=(1, 1))
