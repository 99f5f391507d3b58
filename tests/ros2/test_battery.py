"""The battery the bridge publishes (no DDS needed)."""

from __future__ import annotations

import pytest

pytest.importorskip("cyclonedds", reason="cyclonedds is not installed (pip install 'omnibot[ros2]')")


def test_battery_state_health_and_status_follow_the_thresholds() -> None:
    """omni4's 2S Li-Po: GOOD and DISCHARGING above the 6.6 V stop, DEAD and NOT_CHARGING below it or
    while the controller holds its battery stop; LIPO; the diagnostics' levels with it."""
    from omnibot.robot import load_robot
    from omnibot.ros2.battery import (
        SUPPLY_HEALTH_DEAD,
        SUPPLY_HEALTH_GOOD,
        SUPPLY_STATUS_DISCHARGING,
        SUPPLY_STATUS_NOT_CHARGING,
        battery_health,
        battery_state,
    )

    robot = load_robot("omni4")
    assert [battery_health(robot, v) for v in (7.4, 6.9, 6.7, 6.5, 0.0)] == [
        "ok",
        "low",
        "limited",
        "flat",
        "unknown",
    ]
    assert battery_health(robot, 7.2, stopped=True) == "flat"
    good = battery_state(robot, 7.3, 0)
    assert (good.power_supply_health, good.power_supply_status) == (
        SUPPLY_HEALTH_GOOD,
        SUPPLY_STATUS_DISCHARGING,
    )
    assert good.power_supply_technology == 3  # LIPO
    dead = battery_state(robot, 6.9, 0, stopped=True)
    assert (dead.power_supply_health, dead.power_supply_status) == (
        SUPPLY_HEALTH_DEAD,
        SUPPLY_STATUS_NOT_CHARGING,
    )
