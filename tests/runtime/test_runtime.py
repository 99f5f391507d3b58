"""The runtime's cycle on sim:// in lockstep: a script drives, sinks see every cycle, a broken sink
is dropped without stopping the robot loop, commands are clamped to what the controller accepts."""

from __future__ import annotations

import pytest

from omnibot import collector
from omnibot.client import Pending, RobotClient
from omnibot.control import make_follower, standard_path
from omnibot.estimation import make_estimator
from omnibot.motion import Pose2D, Twist
from omnibot.navigation.session import follower_limits
from omnibot.protocol import codes
from omnibot.protocol.messages import Command, Vel
from omnibot.robot import load_robot
from omnibot.runtime.cycle import Cycle
from omnibot.runtime.runtime import Runtime
from omnibot.runtime.sources import FollowerSource, ScriptSource
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


def test_running_ends_the_commands_start(monkeypatch: pytest.MonkeyPatch) -> None:
    """The loop releases the garbage collector a command's start held (:mod:`omnibot.collector`)."""
    released: list[int] = []
    monkeypatch.setattr(collector, "release", lambda: released.append(1))
    with RobotClient.open("sim://omni4?seed=1", timeout=0.5) as client:
        runtime = Runtime(client, period=0.01)
        runtime.run(duration=0.0)
        runtime.close()
    assert released == [1] and runtime.cycles == 0


@pytest.mark.parametrize("versions", [(2,), (2, 3), codes.VERSIONS])
def test_a_followers_planned_acceleration_goes_only_to_a_controller_that_takes_it(
    versions: tuple[int, ...], monkeypatch: pytest.MonkeyPatch
) -> None:
    """The tracker's VELs carry its profile's acceleration once the controller's HELLO agreed on it:
    version 4 the body's on every VEL (speeding up, then braking, along the line), version 3 the
    speed's (the line is straight, the heading held); a controller that answered 2 gets neither."""
    robot = load_robot("mecanum4")
    path = standard_path("line", size=0.4)
    with RobotClient.open("sim://mecanum4?seed=1&world=empty", robot) as client:
        version = client.hello(versions).version
        assert version == max(versions)
        assert client.takes_vel_accel is (version >= codes.VEL_ACCEL_VERSION)
        assert client.takes_vel_body_accel is (version >= codes.VEL_BODY_ACCEL_VERSION)
        sent: list[Vel] = []
        submit = client.submit

        def recorded(command: Command, timeout: float | None = None) -> Pending:
            if isinstance(command, Vel):
                sent.append(command)
            return submit(command, timeout)

        monkeypatch.setattr(client, "submit", recorded)
        runtime = Runtime(client, period=0.01, estimator=make_estimator("fused", robot, Pose2D(*path.start)))
        follower = FollowerSource(make_follower("tracker", follower_limits(robot, 0.3)), path)
        runtime.add_source(follower)
        client.telemetry(0.01, codes.TEL_MASK)
        runtime.run(until=lambda: follower.finished, duration=20.0)
        runtime.close()
    assert follower.completed and len(sent) > 50
    accels = [v.accel for v in sent]
    bodies = [v.body for v in sent]
    if version == 4:
        assert accels == [0] * len(sent) and None not in bodies[:-1]  # (the last is the end's STOP)
        along = [b[0] for b in bodies if b is not None]  # the line runs along the body's x
        assert max(along) > 50 and min(along) < -50  # cm/s^2: it sped up and braked
    elif version == 3:
        assert bodies == [None] * len(sent)
        assert max(accels) > 50 and min(accels) < -50
    else:
        assert accels == [0] * len(sent) and bodies == [None] * len(sent)


def test_a_broken_telemetry_hook_is_dropped_and_the_loop_still_gets_every_sample(
    caplog: pytest.LogCaptureFixture,
) -> None:
    """A hook (the recorder's, on a full disk) that raises never keeps a sample from the cycles."""
    with RobotClient.open("sim://omni4?seed=1", timeout=0.5) as client:
        script = ScriptSource(lambda t: Twist(0.3, 0.0, 0.0) if t < 0.5 else ScriptSource.END)
        runtime = Runtime(client, period=0.01, sources=[script])
        calls: list[float] = []

        def broken(tel: object) -> None:
            calls.append(0.0)
            raise OSError(28, "No space left on device")

        runtime.telemetry_hooks.append(broken)
        client.telemetry(0.01, codes.TEL_MASK)
        samples: list[int] = []
        runtime.add_sink(lambda cycle: samples.append(len(cycle.telemetry)))
        runtime.run(until=lambda: script.finished)
        runtime.close()
        assert len(calls) == 1 and broken not in runtime.telemetry_hooks
        assert "a telemetry hook failed" in caplog.text
        assert sum(samples) > 10  # the samples still reached the cycles
