"""config_staging.py: robot_config.py's text."""

from __future__ import annotations

import pytest

from omnibot.errors import ConfigError
from omnibot.firmware import config as fwconfig
from omnibot.robot import load_robot


def test_a_number_that_is_not_finite_is_never_written() -> None:
    config = fwconfig.build_config(load_robot("omni4"))
    assert "inf" not in fwconfig.config_module_source(config)
    for broken in ({"speed_max_cms": float("inf")}, {"kt": [[0.0, 1.0], [1.0, float("nan")]]}):
        with pytest.raises(ConfigError, match=r"cannot hold .* every number must be finite") as info:
            fwconfig.config_module_source({**config, **broken})
        assert next(iter(broken)) in str(info.value)
