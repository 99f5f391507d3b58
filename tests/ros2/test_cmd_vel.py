"""The bridge's cmd_vel source without DDS: the newest twist while fresh, ramped at the robot's limits; the
types taken by what the publishers in the graph offer."""

from __future__ import annotations

import json
from collections.abc import Callable
from types import SimpleNamespace
from typing import Any

import pytest

from omnibot.logs import header, schemas
from omnibot.logs.rosmsg import twist
from omnibot.motion import Twist
from omnibot.ros2.cmd_vel import TWIST, TWIST_STAMPED, CmdVelSource
from omnibot.ros2.types import to_dds
from omnibot.runtime import Cycle
from omnibot.teleop import TwistLimits
from tests.ros2.netns_helper import run_in_namespace
from tests.ros2.test_odometry import Node


def test_cmd_vel_ramps_at_the_robots_acceleration_and_falls_silent_when_stale() -> None:
    node = Node()
    source = CmdVelSource(node, limits=TwistLimits(1.0, 5.0, accel=2.0, angular_accel=10.0), period=0.02)  # type: ignore[arg-type]
    message = to_dds(
        schemas.new(TWIST_STAMPED, header=header(0, "base_link"), twist=twist(0.3, 0.0, 0.0)), TWIST_STAMPED
    )
    node.endpoints["cmd_vel"].samples.append(message)
    speeds = []
    for k in range(10):
        proposal = source.propose(Cycle(k, k * 0.02, k * 0.02, None))
        assert proposal is not None
        speeds.append(round(proposal.twist.vx, 3))
    assert speeds == [0.04, 0.08, 0.12, 0.16, 0.2, 0.24, 0.28, 0.3, 0.3, 0.3]
    assert source.body_accel == pytest.approx((0.0, 0.0, 0.0))
    assert source.propose(Cycle(10, 0.2 + source.timeout + 0.01, 0.0, None)) is None  # stale: silent
    unlimited = CmdVelSource(Node())  # type: ignore[arg-type]
    unlimited.reader.samples.append(message)
    proposal = unlimited.propose(Cycle(0, 0.0, 0.0, None))
    assert proposal is not None and proposal.twist == Twist(0.3, 0.0, 0.0)


def publication(typename: str, topic: str = "rt/cmd_vel") -> SimpleNamespace:
    """A DCPSPublication sample as cyclonedds hands it over (the fields the source reads)."""
    pkg, kind, name = typename.split("/")
    return SimpleNamespace(topic_name=topic, type_name=f"{pkg}::{kind}::dds_::{name}_")


def test_a_twist_publisher_in_the_graph_is_taken_and_one_of_another_type_told_of_once() -> None:
    node = Node()
    told: list[tuple[str, str]] = []
    source = CmdVelSource(node, notify=lambda level, text: told.append((level, text)))  # type: ignore[arg-type]
    assert set(source.readers) == {TWIST_STAMPED}
    node.discovered.samples += [
        publication(TWIST),
        publication("std_msgs/msg/String"),
        publication("std_msgs/msg/String"),  # a second writer of it: not told again
        publication("nav_msgs/msg/Path", "rt/path"),  # another topic: none of cmd_vel's business
    ]
    assert source.propose(Cycle(0, 0.0, 0.0, None)) is None
    assert set(source.readers) == {TWIST_STAMPED, TWIST}
    assert told == [
        (
            "warn",
            "cmd_vel: a publisher of std_msgs/msg/String ignored: omnibot drives on "
            "geometry_msgs/msg/Twist or geometry_msgs/msg/TwistStamped",
        )
    ]
    node.endpoints["cmd_vel:Twist"].samples.append(to_dds(twist(0.0, 0.2, 0.0), TWIST))
    proposal = source.propose(Cycle(1, 0.02, 0.02, None))
    assert proposal is not None and proposal.twist == Twist(0.0, 0.2, 0.0)
    stamped = schemas.new(TWIST_STAMPED, header=header(0, "base_link"), twist=twist(0.1, 0.0, 0.0))
    node.endpoints["cmd_vel"].samples.append(to_dds(stamped, TWIST_STAMPED))
    proposal = source.propose(Cycle(2, 0.04, 0.04, None))
    assert proposal is not None and proposal.twist == Twist(0.1, 0.0, 0.0)
    assert source.received == 2


def test_twist_forced_takes_only_twist_and_says_why_of_a_twist_stamped_publisher() -> None:
    node = Node()
    told: list[str] = []
    source = CmdVelSource(node, forced=TWIST, notify=lambda level, text: told.append(text))  # type: ignore[arg-type]
    node.discovered.samples += [publication(TWIST_STAMPED), publication(TWIST)]
    source.propose(Cycle(0, 0.0, 0.0, None))
    assert set(source.readers) == {TWIST}
    assert told == [
        "cmd_vel: a publisher of geometry_msgs/msg/TwistStamped ignored: --twist takes only "
        "geometry_msgs/msg/Twist (without --twist both are taken)"
    ]
    with pytest.raises(ValueError, match="not std_msgs/msg/String"):
        CmdVelSource(node, forced="std_msgs/msg/String")  # type: ignore[arg-type]


def test_every_reader_wakes_the_runtime_when_a_command_arrives() -> None:
    """The source hands the runtime's wake function to each reader, the Twist reader made later too;
    a reader that cannot tell of arrivals leaves the source polled by the cycles."""

    class Telling(Node):
        def __init__(self) -> None:
            super().__init__()
            self.callbacks: dict[str, Callable[[], None]] = {}

        def reader(self, name: str, typename: str) -> Any:
            endpoint = super().reader(name, typename)
            endpoint.on_data = lambda callback: self.callbacks.setdefault(typename, callback)  # type: ignore[attr-defined]
            return endpoint

    node = Telling()
    woken: list[str] = []
    source = CmdVelSource(node)  # type: ignore[arg-type]
    assert not source.event_driven  # no runtime yet
    source.wake_with(lambda: woken.append("ros2"))
    node.discovered.samples.append(publication(TWIST))
    source.discover()
    assert set(node.callbacks) == {TWIST_STAMPED, TWIST} and source.event_driven
    for callback in node.callbacks.values():
        callback()
    assert woken == ["ros2", "ros2"]
    polled = CmdVelSource(Node())
    polled.wake_with(lambda: woken.append("never"))
    assert not polled.event_driven and woken == ["ros2", "ros2"]


def test_the_listeners_go_when_the_node_closes() -> None:
    """A reader that takes cyclonedds' listeners has it set by the source and removed (set to None)
    by the node's closers, before the participant goes."""

    class Listening(Node):
        def __init__(self) -> None:
            super().__init__()
            self.closers: list[Callable[[], object]] = []
            self.set: list[Any] = []

        def reader(self, name: str, typename: str) -> Any:
            endpoint = super().reader(name, typename)
            endpoint.set_listener = self.set.append  # type: ignore[attr-defined]
            return endpoint

    node = Listening()
    source = CmdVelSource(node)  # type: ignore[arg-type]
    source.wake_with(lambda: None)
    assert len(node.set) == 1 and node.set[0] is not None and source.event_driven
    assert node.closers == [source.unlisten]
    for closer in node.closers:
        closer()
    assert node.set[-1] is None and not source.listeners and source.wake is None


EACH = r"""
import json, threading, time
from omnibot.client import robot_session
from omnibot.logs import header, schemas
from omnibot.logs.rosmsg import twist
from omnibot.protocol.messages import Vel
from omnibot.ros2.cmd_vel import CmdVelSource
from omnibot.ros2.dds import Node
from omnibot.ros2.types import to_dds
from omnibot.runtime import Runtime
from omnibot.teleop import Pacer

TS = "geometry_msgs/msg/TwistStamped"
PERIOD = 1.0  # a cycle a second: commands 0.1 s apart go out only if each is sent as it arrives
with robot_session("sim://omni4?seed=2&world=empty", "omni4", timeout=0.5) as session:
    client = session.client
    bridge, teleop = Node(), Node()
    writer = teleop.writer("cmd_vel", TS)
    source = CmdVelSource(bridge, timeout=2.0)  # no limits: no ramp, each VEL carries its command
    runtime = Runtime(client, period=PERIOD, sources=[source])
    sent = []
    submit = client.submit
    def record(command, timeout=None):
        if isinstance(command, Vel):
            sent.append(command.vx)
        return submit(command, timeout)
    client.submit = record
    end = time.monotonic() + 30
    while not (writer.get_matched_subscriptions() and source.reader.get_matched_publications()):
        assert time.monotonic() < end, "never matched"
        time.sleep(0.02)
    published = []

    def drive():  # teleop_twist_joy's thread: five speeds 0.1 s apart
        for k in range(5):
            speed = 0.05 * (k + 1)
            writer.write(to_dds(schemas.new(TS, header=header(0, "base_link"), twist=twist(speed, 0.0, 0.0)), TS))
            published.append(round(speed * 100))
            time.sleep(0.1)

    runtime.start()
    runtime.pacer = Pacer(client, PERIOD)
    thread = threading.Thread(target=drive)
    thread.start()
    runtime.run(duration=0.9)  # the first cycle, then the wait for the second: a second
    thread.join()
    event_driven = source.event_driven
    runtime.close()
    bridge.close(); teleop.close()
print(json.dumps({"published": published, "sent": sent, "cycles": runtime.cycles, "reactions": runtime.reactions,
                  "event_driven": event_driven}))
"""


def test_each_command_goes_out_as_it_arrives_not_at_the_next_cycle() -> None:
    """A teleop stand-in on DDS sends five speeds 0.1 s apart to a runtime whose cycle is a second:
    every one reaches the link, in order, though one cycle ran meanwhile: the others each by a
    reaction of the runtime, woken by the reader's listener."""
    result = json.loads(run_in_namespace(EACH).stdout.strip().splitlines()[-1])
    assert result["event_driven"], result
    assert result["cycles"] == 1, result
    carried = [v for v in result["sent"] if v]
    assert [v for i, v in enumerate(carried) if i == 0 or v != carried[i - 1]] == result["published"], result
    assert result["reactions"] >= len(result["published"]) - result["cycles"], result  # the rest: reactions
