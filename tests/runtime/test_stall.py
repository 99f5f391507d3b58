"""The stall watch on the simulated robot in lockstep, without the simulator's truth (as on a real
robot): a robot driven into the corridor's end wall is stopped and what drove it ends with the
reason; normal follows of every preset on wood and carpet raise no alarm."""

from __future__ import annotations

import pytest

from omnibot.client import RobotClient
from omnibot.control import standard_path
from omnibot.estimation import make_estimator
from omnibot.motion import Pose2D, Twist
from omnibot.navigation import follower_source
from omnibot.protocol import codes
from omnibot.robot import load_robot
from omnibot.runtime.cycle import Cycle
from omnibot.runtime.runtime import Runtime
from omnibot.runtime.sources import ScriptSource
from omnibot.runtime.stall import StallWatch, start_sonars
from omnibot.transport import find_simulator


@pytest.mark.parametrize(
    ("name", "witness"), [("omni4", "sonar"), ("omni3", "tracking"), ("mecanum4", "effort")]
)
def test_a_robot_pinned_against_a_wall_is_stopped_and_its_source_told(name: str, witness: str) -> None:
    robot = load_robot(name)
    with RobotClient.open(f"sim://{name}?seed=1&world=corridor", robot) as client:
        client.use_binary()
        runtime = Runtime(client, period=0.01)  # the wheel-speed loop: full power against the wall
        watch = StallWatch(runtime, robot)  # no truth: the robot's own witnesses
        # from (1, 0) along the corridor at 0.6 m/s for 25 s: its end wall is 9 m away
        script = ScriptSource(lambda t: Twist(0.6, 0.0, 0.0) if t < 25.0 else ScriptSource.END)
        runtime.add_source(script)
        cycles: list[Cycle] = []
        runtime.add_sink(cycles.append)
        start_sonars(client, robot)
        client.telemetry(0.01, codes.TEL_MASK)
        runtime.run(until=lambda: script.finished, duration=30.0)
        sim = find_simulator(client.link)
        assert sim is not None
        pinned_at = sim.pose.x
        runtime.run(duration=0.5)
        runtime.close()
        assert sim.pose.x == pytest.approx(pinned_at, abs=1e-3)
        assert sim.twist.vx == pytest.approx(0.0, abs=1e-3)
        assert client.status().state != codes.STATE_MOVING  # STOP: nothing drives on
        assert runtime.closed_loop
    [stall] = watch.stalls
    assert stall.witness == witness and stall.t < 20.0
    assert script.failure == stall.text and stall.text.startswith("stalled: the wheels say")
    told = [n for c in cycles for n in c.notices if n.text == stall.text]
    assert told and told[0].level == "error" and told[0].source == "script"
    assert 9.4 < pinned_at < 9.95  # against the wall, short of the 15 m it was sent


@pytest.mark.parametrize("surface", ["wood", "carpet"])
@pytest.mark.parametrize("name", ["omni4", "omni3", "mecanum4"])
@pytest.mark.parametrize("closed_loop", [True, False], ids=["wheel-loop", "open-loop"])
def test_normal_follows_raise_no_alarm(name: str, surface: str, closed_loop: bool) -> None:
    robot = load_robot(name)
    path = standard_path("lemniscate", size=1.0, heading="tangent")  # turns and sideways runs
    with RobotClient.open(f"sim://{name}?seed=2&world=empty&surface={surface}", robot) as client:
        estimator = make_estimator("fused", robot, Pose2D(*path.start))
        runtime = Runtime(client, period=0.01, estimator=estimator, wheel_loop=closed_loop)
        watch = StallWatch(runtime, robot)
        follower = follower_source(robot, path, 0.01)
        runtime.add_source(follower)
        client.use_binary()
        client.telemetry(0.01, codes.TEL_MASK)
        runtime.run(duration=1.0)  # standing: the gyro's bias
        runtime.run(until=lambda: follower.finished, duration=40.0)
        runtime.close()
    assert runtime.closed_loop is closed_loop
    assert follower.completed, follower.failure
    assert watch.stalls == []
