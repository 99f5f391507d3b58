"""config_calibration.py: the description's calibration as the config's tables."""

from __future__ import annotations

import pytest

from omnibot.errors import ConfigError
from omnibot.firmware import config as fwconfig
from omnibot.robot import PiecewiseLinear, RollerDragSpec, load_robot


def test_roller_drag_section_in_the_config() -> None:
    robot = load_robot("omni4")
    assert robot.calibration is not None
    coast = PiecewiseLinear(x=(0.0, 0.64), y=(0.0, 0.34))
    drag = RollerDragSpec(cos=(-5.0, -4.0, -5.0, -4.0), sin=(0.5, 0.0, 0.0, 0.0), coast=coast)
    cfg = fwconfig.build_config(
        robot.model_copy(update={"calibration": robot.calibration.model_copy(update={"rollers": drag})})
    )
    assert cfg["roller_cos"] == [-5.0, -4.0, -5.0, -4.0] and cfg["roller_sin"][0] == 0.5
    assert cfg["roller_coast"] == [[0.0, 64.0], [0.0, 0.34]]  # speeds in cm/s, as the controller's V
    three = RollerDragSpec(cos=(0.0,) * 3, sin=(0.0,) * 3)
    with pytest.raises(ConfigError, match="roller drag for 3 wheels on a robot with 4"):
        fwconfig.build_config(
            robot.model_copy(update={"calibration": robot.calibration.model_copy(update={"rollers": three})})
        )
