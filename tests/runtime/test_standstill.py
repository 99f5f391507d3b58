"""The standstill before an autonomous run (``omnibot run --follow``, with or without the
dashboard): the follower is held while the gyro's bias is learned, a person is not, and the
follower then starts on the whole path."""

from __future__ import annotations

from omnibot.client import RobotClient
from omnibot.control import make_follower, standard_path
from omnibot.estimation import make_estimator
from omnibot.motion import Pose2D, Twist
from omnibot.navigation import STANDSTILL
from omnibot.navigation.session import follower_limits
from omnibot.protocol import codes
from omnibot.robot import load_robot
from omnibot.runtime.cycle import Cycle
from omnibot.runtime.runtime import Runtime
from omnibot.runtime.sources import FollowerSource, ScriptSource
from omnibot.runtime.standstill import Standstill


def test_the_follower_waits_out_the_standstill_and_a_person_does_not() -> None:
    robot = load_robot("omni4")
    path = standard_path("line", size=0.3)
    with RobotClient.open("sim://omni4?seed=1&world=empty", robot) as client:
        runtime = Runtime(client, period=0.01, estimator=make_estimator("fused", robot, Pose2D(*path.start)))
        follower = FollowerSource(make_follower("tracker", follower_limits(robot, 0.3)), path)
        person = ScriptSource(lambda t: Twist(0.0, 0.0, 0.2) if t < 0.5 else ScriptSource.END, priority=200)
        runtime.add_source(follower)
        runtime.add_source(person)
        standstill = Standstill(runtime, STANDSTILL, follower.priority)
        cycles: list[Cycle] = []
        runtime.add_sink(cycles.append)
        client.telemetry(0.01, codes.TEL_MASK)
        runtime.run(until=lambda: follower.finished, duration=30.0)
        runtime.close()
    assert follower.completed and follower.overrides == 0  # it had not driven before: the whole path
    drove = [
        c for c in cycles if c.decision.source == "follower" and c.sent is not None and not c.sent.is_zero
    ]
    assert standstill.until is not None and drove[0].t >= standstill.until
    assert drove[0].t - cycles[0].t < STANDSTILL + 0.2
    held = [c for c in cycles if c.decision.lock == "standstill"]
    assert (
        held
        and held[0].decision.reason == "follower held by the standstill: the gyro's bias is learned (3 s)"
    )
    assert [c.decision.source for c in cycles[:5]] == ["script"] * 5  # the person is not held
