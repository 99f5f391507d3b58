"""The bridge's time: :class:`~omnibot.ros2.clock.Timeline`, and a genuine rclpy node with
``use_sim_time`` following ``/clock`` through a stall of the bridge (SIGSTOP for 1 s), in a private
network namespace."""

from __future__ import annotations

import importlib.util
import itertools
import json
import statistics

import pytest

from omnibot.ros2.clock import Timeline
from tests.ros2.netns_helper import run_in_namespace
from tests.ros2.rclpy_scripts import beside_bridge


def test_timeline_places_every_robot_alike_and_clock_never_goes_back() -> None:
    walls = iter([5_000, 9_000])
    timeline = Timeline(wall_ns=lambda: next(walls))
    assert timeline.origin(2.0) == (2.0, 5_000)
    assert timeline.origin(7.5) == (2.0, 5_000)  # a second robot: the first one's origin
    assert timeline.advance(10) and timeline.clock_ns == 10
    assert not timeline.advance(10)  # the other robot's cycle at the same time: not twice
    assert not timeline.advance(4)  # nor back
    assert timeline.advance(11)


STALL = r"""
from rclpy.parameter import Parameter
from nav_msgs.msg import Odometry
from rosgraph_msgs.msg import Clock

node = Node("sim_time_user", parameter_overrides=[Parameter("use_sim_time", Parameter.Type.BOOL, True)])
ns = lambda t: t.sec * 1_000_000_000 + t.nanosec
odom, clocks = [], []  # odom: (stamp, the node's clock, the wall clock) at each message
node.create_subscription(
    Odometry, "odom", lambda m: odom.append((ns(m.header.stamp), node.get_clock().now().nanoseconds, time.time_ns())), 10
)
node.create_subscription(Clock, "/clock", lambda m: clocks.append(ns(m.clock)), 10)

spin_until(lambda: len(odom) >= 60, 90)  # the bridge's start, then about a second of odom
before = len(odom)
os.kill(bridge.pid, signal.SIGSTOP)
time.sleep(1.0)
os.kill(bridge.pid, signal.SIGCONT)
spin_until(lambda: len(odom) >= before + 100, 60)
bridge.terminate()
out, _ = bridge.communicate(timeout=30)
print(json.dumps({"odom": odom, "before": before, "clocks": clocks, "bridge": out[-2000:]}))
node.destroy_node()
rclpy.shutdown()
"""


@pytest.mark.skipif(
    importlib.util.find_spec("rclpy") is None,
    reason="rclpy is not installed (the test-only extra: pip install 'omnibot[ros2-test]')",
)
def test_a_use_sim_time_node_follows_the_simulation_through_a_stall() -> None:
    """``/clock`` is there, never goes back, and is the time odom is stamped in: a node with
    use_sim_time sees each odom as new after the bridge was stopped for 1 s as before it, while on
    its wall clock the same stamps fell about that second behind (what happened before ``/clock``:
    a permanent offset). Medians, so a loaded machine's late deliveries do not decide."""
    script = beside_bridge(["--port", "sim://omni4", "--duration", "150"], STALL)
    result = json.loads(run_in_namespace(script, timeout=240).stdout.strip().splitlines()[-1])
    odom, before, clocks = result["odom"], result["before"], result["clocks"]
    assert before >= 60 and len(odom) >= before + 100, result["bridge"]
    assert clocks, "no /clock"
    assert all(b >= a for a, b in itertools.pairwise(clocks)), "/clock went back"
    stamps = [s for s, _, _ in odom]
    assert all(b > a for a, b in itertools.pairwise(stamps)), "odom stamps not monotonic"
    # odom may overtake the /clock of its own cycle (two topics): the last odom taken may be a cycle
    # (20 ms) ahead of the last /clock taken
    assert max(stamps) <= max(clocks) + 50_000_000
    sim_lag = [(now - s) / 1e9 for s, now, _ in odom]
    wall_lag = [(wall - s) / 1e9 for s, _, wall in odom]
    pre, post = slice(before // 2, before), slice(len(odom) - 50, len(odom))
    # odom may overtake the /clock of its own cycle (two topics): a cycle (20 ms) ahead at most
    assert min(sim_lag[before // 2 :]) > -0.05, sim_lag
    sim_shift = statistics.median(sim_lag[post]) - statistics.median(sim_lag[pre])
    wall_shift = statistics.median(wall_lag[post]) - statistics.median(wall_lag[pre])
    print(f"after the stall: sim-time lag moved {sim_shift:+.3f} s, wall-clock lag {wall_shift:+.3f} s")
    assert wall_shift > 0.5  # the stall happened: the simulation is behind the wall clock for good
    assert abs(sim_shift) < 0.3  # and on the clock the user is told to use, nothing moved
