"""What the bridge's sink publishes that needs no DDS: whose diagnostics they are."""

from __future__ import annotations

import pytest

pytest.importorskip("cyclonedds", reason="cyclonedds is not installed (pip install 'omnibot[ros2]')")

from omnibot.ros2.bridge import Diagnosed


def test_a_robot_in_a_namespace_has_its_name_in_every_status_and_as_hardware_id() -> None:
    r1 = Diagnosed.of("omni4", "/r1")
    r2 = Diagnosed.of("omni4", "r2")
    control = r1.status(0, "control", "ok", {"source": "none"})
    assert (control.name, control.hardware_id) == ("omnibot r1: control", "r1")
    assert r2.status(0, "control", "ok", {}).name == "omnibot r2: control"
    alone = Diagnosed.of("omni4")  # one robot, no namespace: the description's name
    path = alone.status(1, "path", "failed", {"state": "failed"})
    assert (path.name, path.hardware_id, path.level) == ("omnibot: path", "omni4", 1)
    assert [(kv.key, kv.value) for kv in path.values] == [("state", "failed")]


def test_battery_state_health_and_status_follow_the_thresholds() -> None:
    """omni4's 2S Li-Po: GOOD and DISCHARGING above the 6.6 V stop, DEAD and NOT_CHARGING below it or
    while the controller holds its battery stop; LIPO; the diagnostics' levels with it."""
    from omnibot.robot import load_robot
    from omnibot.ros2.bridge import (
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
