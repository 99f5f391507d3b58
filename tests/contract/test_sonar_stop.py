"""The sonar stop in the room world (fixed seeds): the robot stops before the wall at every speed and
angle it allows for, travel no sonar covers is limited or refused, and with the stop off nothing
changes. On the lockstep simulator (``sim``) and on the Arduino UNO firmware in simavr with the same
physics in the loop (``uno``, and ``mega``: its Arduino Mega 2560 build; docs/uno.md; skipped with
the reason without the AVR tools), timed by
the simulator's clock. benchmarks/sonar_stop.py runs the full grid."""

from __future__ import annotations

import math
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Protocol

import pytest

from omnibot.client import ControllerError, EventRecorder, RobotClient, WarnEvent
from omnibot.protocol import codes
from omnibot.robot import RobotDescription
from omnibot.sim import SimDevice, Simulator
from omnibot.transport import LockstepLink

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


class Device(Protocol):
    """What the tests read of the robot: the simulator (ground truth) and the description."""

    sim: Simulator
    robot: RobotDescription


@pytest.fixture(params=["sim", "uno", "mega"])
def backend(request: pytest.FixtureRequest) -> str:
    if request.param in ("uno", "mega"):
        from omnibot.uno import missing_tools

        reason = missing_tools()
        if reason:
            pytest.skip(f"{request.param} backend: {reason}")
    return str(request.param)


@contextmanager
def room(
    backend: str, angle_deg: float, course_deg: float = 0.0, seed: int = 1
) -> Iterator[tuple[RobotClient, Device]]:
    pose = start_pose(angle_deg, course_deg)
    if backend in ("uno", "mega"):
        from omnibot.uno import UnoLink
        from omnibot.uno.hil import UnoHil

        hil = UnoHil("omni4", world="room", seed=seed, start_pose=pose, board=backend)
        with RobotClient(UnoLink(hil, f"uno://omni4?board={backend}"), "omni4", timeout=2.0) as client:
            yield client, hil
        return
    device = SimDevice("omni4", world="room", seed=seed, start_pose=pose)
    with RobotClient(LockstepLink(device), "omni4", timeout=2.0) as client:
        yield client, device


def wait(client: RobotClient, device: Device, seconds: float) -> None:
    """Let ``seconds`` of the simulator's time pass (the emulated UNO may run slower than the wall)."""
    end = device.sim.time + seconds
    while device.sim.time < end:
        client.sleep(0.02)


def gap(device: Device) -> float:
    """Least distance between the robot's outline and the west wall, m."""
    pose = device.sim.pose
    c, s = math.cos(pose.theta), math.sin(pose.theta)
    return min(pose.x + c * x - s * y for x, y in device.robot.footprint.outline()) - WALL


def drive(client: RobotClient, device: Device, seconds: float) -> float:
    """Let the robot run for ``seconds`` of simulated time; the least wall gap on the way (m)."""
    least = gap(device)
    end = device.sim.time + seconds
    while device.sim.time < end:
        client.sleep(0.02)
        least = min(least, gap(device))
    return least


@pytest.mark.parametrize("stop", [0.10, 0.25])
@pytest.mark.parametrize("angle", [30, 90, 135])
@pytest.mark.parametrize("speed", [0.5, 1.0])
def test_stops_before_the_wall(backend: str, speed: float, angle: int, stop: float) -> None:
    with room(backend, angle) as (client, device):
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


def test_uncovered_travel_is_limited(backend: str) -> None:
    with room(backend, 90, course_deg=90) as (client, device):
        rec = EventRecorder()
        client.add_listener(rec, WarnEvent)
        client.sonar(1, 0.06, 0.0, 0.0, 0.25)
        client.move(math.inf, 1.0, course=math.pi / 2)
        wait(client, device, 1.5)
        speed = math.hypot(device.sim.twist.vx, device.sim.twist.vy)
        assert 0.2 < speed < 0.36  # omni4's uncovered speed, 0.3 m/s
        assert [w.code for w in rec.of(WarnEvent)] == [codes.W_UNCOVERED]
        client.stop()


def test_uncovered_travel_is_refused_with_mode_bit_3(backend: str) -> None:
    with room(backend, 90, course_deg=90) as (client, device):
        client.mode(codes.MODE_REFUSE_UNCOVERED)
        client.sonar(1, 0.06, 0.0, 0.0, 0.25)
        with pytest.raises(ControllerError) as info:
            client.move(math.inf, 1.0, course=math.pi / 2)
        assert info.value.code == codes.E_UNCOVERED
        wait(client, device, 0.5)
        assert device.sim.pose.x == pytest.approx(start_pose(90, 90)[0], abs=1e-3)
        assert client.status().mode == codes.MODE_REFUSE_UNCOVERED


def test_stop_off_drives_as_before(backend: str) -> None:
    """RANGE events without a stop threshold: full speed sideways and into the wall, no warnings."""
    with room(backend, 90) as (client, device):
        rec = EventRecorder()
        client.add_listener(rec, WarnEvent)
        client.sonar(1, 0.06, 0.0, 1.0, 0.0)
        client.move(math.inf, 1.0)
        wait(client, device, 2.5)
        assert device.sim.collisions  # nothing stops it
        assert rec.events == []
        client.stop()
