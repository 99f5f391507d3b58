"""One runtime on sim:// with a follower, a pad and the dashboard: who drives, and who is told what.

The dashboard's link runs its periods by hand on a fake wall clock (tests.web.test_link.Stepper), so
simulated time follows it and everything is deterministic. Motion is checked on the simulator's
ground truth.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any

import numpy as np
import pytest

from omnibot.client import RobotClient
from omnibot.control import Path, make_follower
from omnibot.estimation import make_estimator
from omnibot.motion import Pose2D
from omnibot.navigation.session import follower_limits
from omnibot.robot import load_robot
from omnibot.runtime.core import BATTERY_LATCHED_TEXT, LATCHED_TEXT
from omnibot.runtime.sinks import NoticePrinter
from omnibot.runtime.sources import FollowerSource
from omnibot.teleop import PadSource, TeleopConfig, TwistLimits
from omnibot.web.link import RobotLink
from omnibot.web.messages import EStop
from tests.teleop.fakes import ScriptedSource, seed_pad, truth
from tests.web.test_link import Stepper

CONFIG = TeleopConfig(speed_max=0.4)


@dataclass
class Rig:
    stepper: Stepper
    link: RobotLink
    follower: FollowerSource
    pad: PadSource
    said: list[str]
    path: Path
    stick: dict[str, object]

    def run(self, seconds: float) -> dict[str, Any]:
        return self.stepper.run(seconds)

    @property
    def pose(self) -> tuple[float, float]:
        p = truth(self.link.client).pose
        return (p.x, p.y)


@pytest.fixture
def rig() -> Iterator[Rig]:
    robot = load_robot("omni4")
    client = RobotClient.open("sim://omni4?world=room&seed=1", timeout=0.5)
    link = RobotLink(client, robot, CONFIG)
    x0, y0, th0 = link.pose or (0.0, 0.0, 0.0)
    runtime = link.runtime
    runtime.estimator = make_estimator("fused", robot, Pose2D(x0, y0, th0))  # the world frame
    n = 61  # 1.2 m along the room's x axis, heading kept
    path = Path(np.linspace(x0, x0 + 1.2, n), np.full(n, y0), np.full(n, th0))
    follower = FollowerSource(
        make_follower("tracker", follower_limits(robot, 0.25), rate=1.0 / CONFIG.period),
        path,
        watchdog=0.25,
    )
    stick: dict[str, object] = {"reading": None}
    pad = PadSource(
        ScriptedSource(lambda now: stick["reading"]),
        CONFIG,
        TwistLimits.from_limits(client.limits, CONFIG),
        name="pad",
        priority=200,
    )
    said: list[str] = []
    runtime.add_source(pad)
    runtime.add_source(follower)
    runtime.add_sink(NoticePrinter(said.append))  # the pad's terminal
    stepper = Stepper(link)
    yield Rig(stepper, link, follower, pad, said, path, stick)
    link.stop()
    assert client.link.closed


def test_follower_pad_and_page_share_one_runtime(rig: Rig) -> None:
    start = rig.pose
    state = rig.run(1.0)  # the follower drives along +x
    assert state["drive"]["control"] == "follower"
    assert rig.pose[0] - start[0] > 0.1 and abs(rig.pose[1] - start[1]) < 0.02
    # the pad's deadman takes over: sideways, to the left
    rig.stick["reading"] = seed_pad(y=1.0)
    state = rig.run(0.6)
    assert state["drive"]["control"] == "pad"
    assert state["drive"]["reason"] == "pad (priority 200) over follower"
    y_pad = rig.pose[1]
    assert y_pad - start[1] > 0.08
    assert rig.follower.overrides == 1 and not rig.follower.finished
    # releasing it hands back: the stop sequence, the pad's timeout, then the follower again
    rig.stick["reading"] = seed_pad(enable=False)
    state = rig.run(1.0)
    assert state["drive"]["control"] == "follower"
    x_back = rig.pose[0]
    state = rig.run(2.0)  # straight back to the path (farther than 2 cm), then along the rest
    assert rig.pose[0] - x_back > 0.1 and abs(rig.pose[1] - start[1]) < 0.02
    # the page's emergency stop overrides everything: the follower's run ends, the pad cannot drive
    rig.link.submit(EStop(type="estop"))
    rig.stick["reading"] = seed_pad(x=1.0)
    state = rig.run(0.6)
    assert state["drive"]["state"] == "estop" and state["drive"]["control"] == ""
    assert "held by emergency stop (page)" in str(state["drive"]["reason"])
    assert rig.follower.finished and "emergency stop (page)" in rig.follower.failure
    twist = truth(rig.link.client).twist
    assert math.hypot(twist.vx, twist.vy) < 0.01
    # every front end heard who took control
    logs = rig.stepper.logs()
    for text in ("in control: follower", "in control: pad (priority 200) over follower"):
        assert any(line.startswith(text) for line in logs)
    assert not any(line.startswith("in control") for line in rig.said)  # a terminal: no chatter


def test_a_latched_sonar_stop_is_reported_to_every_front_end(rig: Rig) -> None:
    client = rig.link.client
    client.sonar(1, period=0.06, stop=5.0)  # the far wall is nearer than 5 m: moving latches the stop
    state = rig.run(1.0)
    assert state["drive"]["latched"] is True
    assert rig.follower.finished and rig.follower.failure == "emergency stop latched on the controller"
    assert LATCHED_TEXT in rig.said  # the pad's terminal
    assert LATCHED_TEXT in rig.stepper.logs()  # the page
    assert any(line.startswith("WARN 13") for line in rig.stepper.logs())
    # the pad is refused while latched, and a fresh press of its deadman releases the stop
    client.sonar(1, period=0.06, stop=0.0)
    rig.stick["reading"] = seed_pad(x=1.0)
    x0 = rig.pose[0]
    state = rig.run(0.8)
    assert state["drive"]["control"] == "pad" and state["drive"]["latched"] is False
    assert "emergency stop released by a fresh press of the deadman" in rig.said
    assert rig.pose[0] - x0 > 0.05


def test_a_flat_battery_is_reported_to_every_front_end(rig: Rig) -> None:
    """The simulated pack run flat (charge 0: 6.54 V open-circuit, below the 6.6 V stop): the
    controller warns and latches its battery stop; the terminal, the page's log and its state frame
    say so and why, and the pad cannot release it with a fresh press while the pack stays flat."""
    sim = rig.link.client.link.device.sim  # type: ignore[attr-defined]
    state = rig.run(0.5)
    assert state["battery_level"] == "ok"
    sim.physics.battery_charge = [0.0]
    state = rig.run(5.0)
    assert state["drive"]["latched"] is True and state["drive"]["latch_reason"] == "battery"
    assert state["robot_state"] == "battery stop" and state["battery_level"] == "flat"
    assert rig.follower.finished and "battery" in rig.follower.failure
    low = [line for line in rig.said if line.startswith("battery low")]
    assert low and " V:" in low[0]  # with the voltage the controller reported
    assert BATTERY_LATCHED_TEXT in rig.said and BATTERY_LATCHED_TEXT in rig.stepper.logs()
    logs = rig.stepper.logs()
    for code in (19, 20, 43):
        assert any(line.startswith(f"WARN {code}") for line in logs), code
    rig.stick["reading"] = seed_pad(x=1.0)  # a fresh press sends STOP: the flat pack keeps the stop
    x0 = rig.pose[0]
    state = rig.run(0.8)
    assert state["drive"]["latched"] is True and abs(rig.pose[0] - x0) < 0.01
