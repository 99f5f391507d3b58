"""The sonar stop in the room world on the lockstep simulator (fixed seeds): the robot stops before
the wall at every speed and angle it allows for, travel no sonar covers is limited or refused, and
with the stop off nothing changes. benchmarks/sonar_stop.py runs the full grid."""

from __future__ import annotations

import math
from collections.abc import Iterator
from contextlib import contextmanager

import pytest

from omnibot.client import ControllerError, EventRecorder, RobotClient, WarnEvent
from omnibot.protocol import codes
from omnibot.sim.device import SimDevice
from omnibot.transport.lockstep import LockstepLink

WALL = 0.0  # the room's west wall, x = 0
AIM = 1.6  # where on it the path aims, y
RUN_UP = 1.4


def start_pose(angle_deg: float, course_deg: float) -> tuple[float, float, float]:
    travel = math.radians(90.0 + angle_deg)  # 90 degrees: head-on, towards -x
    return (
        WALL - RUN_UP * math.cos(travel),
        AIM - RUN_UP * math.sin(travel),
        travel - math.radians(course_deg),
    )


@contextmanager
def room(angle_deg: float, course_deg: float = 0.0, seed: int = 1) -> Iterator[tuple[RobotClient, SimDevice]]:
    device = SimDevice("omni4", world="room", seed=seed, start_pose=start_pose(angle_deg, course_deg))
    with RobotClient(LockstepLink(device), "omni4", timeout=2.0) as client:
        yield client, device


def gap(device: SimDevice) -> float:
    """Least distance between the robot's outline and the west wall, m."""
    pose = device.sim.pose
    c, s = math.cos(pose.theta), math.sin(pose.theta)
    return min(pose.x + c * x - s * y for x, y in device.robot.footprint.outline()) - WALL


def drive(client: RobotClient, device: SimDevice, seconds: float) -> float:
    """Let the robot run for ``seconds``; the least wall gap on the way (m)."""
    least = gap(device)
    end = client.clock.now() + seconds
    while client.clock.now() < end:
        client.sleep(0.02)
        least = min(least, gap(device))
    return least


@pytest.mark.parametrize("stop", [0.10, 0.25])
@pytest.mark.parametrize("angle", [30, 90, 135])
@pytest.mark.parametrize("speed", [0.5, 1.0])
def test_stops_before_the_wall(speed: float, angle: int, stop: float) -> None:
    with room(angle) as (client, device):
        rec = EventRecorder()
        client.add_listener(rec, WarnEvent)
        client.sonar(1, 0.06, 0.0, 0.0, stop)
        client.move(math.inf, speed)
        least = drive(client, device, 3.5)
        assert device.sim.collisions == []
        assert least > 0.01
        assert [w.code for w in rec.of(WarnEvent)] in (
            [codes.W_SONAR_STOP],
            [codes.W_SONAR_LIMIT, codes.W_SONAR_STOP],
        )
        assert client.status().estop
        assert math.hypot(device.sim.twist.vx, device.sim.twist.vy) < 0.01


def test_uncovered_travel_is_limited() -> None:
    with room(90, course_deg=90) as (client, device):
        rec = EventRecorder()
        client.add_listener(rec, WarnEvent)
        client.sonar(1, 0.06, 0.0, 0.0, 0.25)
        client.move(math.inf, 1.0, course=math.pi / 2)
        client.sleep(1.5)
        speed = math.hypot(device.sim.twist.vx, device.sim.twist.vy)
        assert 0.2 < speed < 0.36  # omni4's uncovered speed, 0.3 m/s
        assert [w.code for w in rec.of(WarnEvent)] == [codes.W_UNCOVERED]
        client.stop()


def test_uncovered_travel_is_refused_with_mode_bit_3() -> None:
    with room(90, course_deg=90) as (client, device):
        client.mode(codes.MODE_REFUSE_UNCOVERED)
        client.sonar(1, 0.06, 0.0, 0.0, 0.25)
        with pytest.raises(ControllerError) as info:
            client.move(math.inf, 1.0, course=math.pi / 2)
        assert info.value.code == codes.E_UNCOVERED
        client.sleep(0.5)
        assert device.sim.pose.x == pytest.approx(start_pose(90, 90)[0], abs=1e-3)
        assert client.status().mode == codes.MODE_REFUSE_UNCOVERED


def test_stop_off_drives_as_before() -> None:
    """RANGE events without a stop threshold: full speed sideways and into the wall, no warnings."""
    with room(90) as (client, device):
        rec = EventRecorder()
        client.add_listener(rec, WarnEvent)
        client.sonar(1, 0.06, 0.0, 1.0, 0.0)
        client.move(math.inf, 1.0)
        client.sleep(2.5)
        assert device.sim.collisions  # nothing stops it
        assert rec.events == []
        client.stop()
