"""Whose diagnostics the bridge publishes (no DDS needed)."""

from __future__ import annotations

import pytest

pytest.importorskip("cyclonedds", reason="cyclonedds is not installed (pip install 'omnibot[ros2]')")

from omnibot.ros2.diagnostics import Diagnosed


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
