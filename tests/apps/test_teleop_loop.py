"""Teleop on the simulated robot: it drives, and every way of letting go stops it.

The loop is paced by a fake wall clock, so simulated time follows it exactly and the tests are
deterministic and fast. "Stopped" is checked on the simulator's ground truth.
"""

from __future__ import annotations

import math
from collections.abc import Iterator

import pytest

from omnibot.apps.teleop_loop import Teleop
from omnibot.client import EventRecorder, IdleEvent, RobotClient
from omnibot.teleop import Pacer, TeleopConfig, Why
from tests.teleop.fakes import FakeWall, ScriptedSource, seed_pad, truth

CONFIG = TeleopConfig(speed_max=0.5)


@pytest.fixture
def client() -> Iterator[RobotClient]:
    with RobotClient.open("sim://omni4?seed=1", timeout=0.25) as c:
        yield c


def make(
    client: RobotClient, script, config: TeleopConfig = CONFIG
) -> tuple[Teleop, FakeWall, list[tuple[float, tuple[float, ...]]]]:
    wall = FakeWall()
    sent: list[tuple[float, tuple[float, ...]]] = []
    real_vel = client.vel

    def vel(
        vx: float,
        vy: float,
        w: float,
        timeout: float,
        accel: float = 0.0,
        body_accel: tuple[float, float, float] | None = None,
    ):
        sent.append((wall(), (vx, vy, w, timeout)))
        return real_vel(vx, vy, w, timeout, accel, body_accel)

    client.vel = vel  # type: ignore[method-assign]
    pacer = Pacer(client, config.period, wall=wall, sleep=wall.sleep)
    messages: list[str] = []
    teleop = Teleop(client, config, ScriptedSource(script), pacer=pacer, on_message=messages.append)
    return teleop, wall, sent


def speed(client: RobotClient) -> float:
    twist = truth(client).twist
    return float(math.hypot(twist.vx, twist.vy) + abs(twist.w) * 0.1)


def test_drives_forward_in_real_time(client: RobotClient) -> None:
    teleop, wall, sent = make(client, lambda t: seed_pad(x=1.0))
    start = truth(client).pose
    teleop.run(duration=1.0)
    assert wall() == pytest.approx(1.0 + CONFIG.stop_repeats * CONFIG.period, abs=0.06)
    assert client.clock.now() == pytest.approx(wall(), abs=0.06)  # simulated time kept with the wall
    end = truth(client).pose
    assert end.x - start.x > 0.3 and abs(end.y - start.y) < 0.05
    driving = [args for _, args in sent if args[0] != 0]
    assert driving and all(args == (0.5, 0.0, 0.0, CONFIG.vel_timeout) for args in driving)
    assert len(driving) == pytest.approx(20, abs=1)  # one VEL per period at autorepeat_rate


def run_until_stopped(
    client: RobotClient,
    teleop: Teleop,
    wall: FakeWall,
    sent: list[tuple[float, tuple[float, ...]]],
    seconds: float,
) -> None:
    teleop.run(duration=seconds)
    t_end = max(t for t, args in sent if args[0] != 0)
    zeros = [t for t, args in sent if args[:3] == (0.0, 0.0, 0.0) and t > t_end]
    assert len(zeros) == CONFIG.stop_repeats  # repeated zero command, one per period
    assert zeros[0] - t_end == pytest.approx(CONFIG.period, abs=1e-6)
    assert speed(client) < 0.01  # the robot is still


@pytest.mark.parametrize(
    ("script", "why"),
    [
        (lambda t: seed_pad(x=1.0, enable=t < 0.6), Why.RELEASED),
        (lambda t: seed_pad(x=1.0) if t < 0.6 else None, Why.LOST),
        (lambda t: seed_pad(x=1.0) if t < 0.6 else "stale", Why.QUIET),
    ],
    ids=["enable-released", "pad-unplugged", "input-frozen"],
)
def test_letting_go_stops_the_robot(client: RobotClient, script, why: Why) -> None:
    teleop, wall, sent = make(client, script)
    rec = EventRecorder()
    client.add_listener(rec, IdleEvent)
    run_until_stopped(client, teleop, wall, sent, 2.0)
    assert teleop.deadman.last_end is why
    # after the last zero VEL the controller's watchdog ends VEL (its wheel-speed loop holds the
    # wheels until they stand still): IDLE, and teleop falls silent
    assert rec.of(IdleEvent)
    last = max(t for t, _ in sent)
    assert wall() - last > CONFIG.vel_timeout


def test_input_freeze_is_noticed_within_input_timeout(client: RobotClient) -> None:
    teleop, _wall, sent = make(client, lambda t: seed_pad(x=1.0) if t < 0.6 else "stale")
    teleop.run(duration=1.6)
    t_end = max(t for t, args in sent if args[0] != 0)
    assert t_end - 0.6 == pytest.approx(CONFIG.input_timeout, abs=CONFIG.period + 1e-6)


def test_a_teleop_that_dies_mid_drive_is_stopped_by_the_watchdog(client: RobotClient) -> None:
    teleop, _wall, _sent = make(client, lambda t: seed_pad(x=1.0))
    rec = EventRecorder()
    client.add_listener(rec, IdleEvent)
    for _ in range(20):  # drive 1 s, then the process "hangs": no more commands, no stop sequence
        teleop.step()
        teleop.pacer.wait()
    assert speed(client) > 0.3
    died = client.clock.now()
    client.sleep(CONFIG.vel_timeout + 0.1)
    assert not rec.of(IdleEvent) and speed(client) < 0.3  # the wheel loop brakes at 2 m/s^2 (omni4)
    client.sleep(0.5)
    idle = rec.of(IdleEvent)
    # the watchdog, then down from 0.5 m/s in 0.25 s, and the wheels standing still for a window
    assert idle and idle[0].time - died <= CONFIG.vel_timeout + 0.25 + 0.15
    assert speed(client) < 0.01


def test_diagonal_full_stick_keeps_its_direction(client: RobotClient) -> None:
    teleop, _, sent = make(client, lambda t: seed_pad(x=1.0, y=1.0, yaw=0.5))
    teleop.run(duration=0.2)
    vx, vy, w, _ = sent[0][1]
    assert vx == pytest.approx(vy)  # 45 degrees, as the stick
    assert math.hypot(vx, vy) == pytest.approx(0.5)  # scaled as a whole down to speed_max
    assert w / vx == pytest.approx(0.5 * 3.5 * (1 - 0.05 / 0.5) / (1 - 0.05) / 3.5, rel=1e-6)


def test_emergency_stop_latch_is_released_only_by_a_fresh_press() -> None:
    with RobotClient.open("sim://omni4?seed=1&world=room", timeout=0.25) as client:
        client.sonar(1, period=0.06, stop=5.0)  # the far wall is nearer than 5 m: moving latches the e-stop
        teleop, _wall, _sent = make(client, lambda t: seed_pad(x=1.0))
        teleop.run(duration=0.6)  # the deadman held all along: teleop reports the latch, never releases it
        assert teleop.latched and teleop.sent.errors > 0
        vel_before = teleop.sent.vel
        client.sonar(1, period=0.06, stop=0.0)
        start = truth(client).pose
        teleop.run(duration=0.6)  # run() ended with the stop sequence: this is a fresh press
        assert not teleop.latched
        assert teleop.sent.vel > vel_before
        assert truth(client).pose.x - start.x > 0.1
