"""The runtime's cycle on sim:// in lockstep: a script drives, sinks see every cycle, a broken sink
is dropped without stopping the robot loop, commands are clamped to what the controller accepts."""

from __future__ import annotations

import math

import pytest

from omnibot.client import RobotClient
from omnibot.motion import Twist
from omnibot.runtime.cycle import Cycle
from omnibot.runtime.runtime import Runtime, clamp_to
from omnibot.runtime.sources import ScriptSource
from tests.teleop.fakes import truth


def test_a_script_drives_and_every_sink_sees_every_cycle(caplog: pytest.LogCaptureFixture) -> None:
    with RobotClient.open("sim://omni4?seed=1", timeout=0.5) as client:
        script = ScriptSource(lambda t: Twist(0.3, 0.0, 0.0) if t < 1.0 else ScriptSource.END)
        runtime = Runtime(client, period=0.01, sources=[script])
        seen: list[Cycle] = []

        def broken(cycle: Cycle) -> None:
            raise RuntimeError("a view that fails")

        runtime.add_sink(seen.append)
        runtime.add_sink(broken)
        x0 = truth(client).pose.x
        runtime.run(until=lambda: script.finished)
        runtime.close()
        assert broken not in runtime.sinks and "a runtime sink failed" in caplog.text
        assert len(seen) == runtime.cycles and 95 <= len(seen) <= 105  # 1 s at 100 Hz, on the link clock
        assert [c.decision.source for c in seen[:-1]] == ["script"] * (len(seen) - 1)
        assert all(c.sent == Twist(0.3, 0.0, 0.0) for c in seen[:-1])
        assert seen[0].notices[0].text == "in control: script (priority 50)"
        assert runtime.sent.vel == len(seen) - 1 and runtime.sent.errors == 0
        assert sum(len(c.telemetry) for c in seen) == 0  # nobody asked for telemetry
        assert truth(client).pose.x - x0 > 0.2


def test_commands_are_clamped_to_the_controllers_limits() -> None:
    with RobotClient.open("sim://omni4", timeout=0.5) as client:
        limits = client.limits
    vmax = (limits.speed_max_cms - 1.0) / 100.0
    fast = clamp_to(limits, Twist(10.0, 10.0, 100.0))
    assert fast.speed == pytest.approx(vmax) and fast.vx == pytest.approx(fast.vy)
    assert fast.w == pytest.approx(math.radians(limits.rate_max_dps - 1.0))
    assert clamp_to(limits, Twist(0.1, -0.1, -0.5)) == Twist(0.1, -0.1, -0.5)
