"""The estimator registry: the estimators a robot's sensors allow, by name."""

from __future__ import annotations

import pytest

from omnibot.errors import ConfigError
from omnibot.estimation.estimator import PoseEstimator
from omnibot.estimation.registry import ESTIMATORS, estimator_names, make_estimator
from omnibot.robot import load_robot


def test_registry_lists_what_the_sensors_allow() -> None:
    assert set(estimator_names(load_robot("omni4"))) == {
        "fused",
        "encoders+gyro",
        "encoders+raw-gyro",
        "encoders",
    }
    assert set(estimator_names(load_robot("omni3"))) == set(ESTIMATORS)
    assert make_estimator("fused", load_robot("omni3")).translation == "tracking"  # type: ignore[attr-defined]
    with pytest.raises(ConfigError, match="unknown estimator 'fusd'"):
        make_estimator("fusd", load_robot("omni4"))
    with pytest.raises(ConfigError, match="tracking wheels"):
        make_estimator("tracking+gyro", load_robot("omni4"))
    with pytest.raises(ConfigError, match="heading source"):
        PoseEstimator(load_robot("omni4"), heading="compass")
