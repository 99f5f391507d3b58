"""Stopping and not moving: STOP over an endless DELTA, the sonar emergency-stop latch, the VEL
watchdog, an open-loop VEL's wheels below the dead band, simulation mode (powers computed, none
applied); and one physics check (sim backends)."""

from __future__ import annotations

import math

import pytest

from omnibot.client import (
    EmergencyStopLatched,
    EventRecorder,
    IdleEvent,
    RangeEvent,
    RobotClient,
    Telemetry,
    WarnEvent,
)
from omnibot.protocol import codes

from .conftest import Backend, ControllerClock, make_client


def test_stop_interrupts_infinite_delta(client: RobotClient) -> None:
    rec = EventRecorder()
    client.on_idle(rec)
    for p in client.submit_text("MOVE,2,40,0,0;DELTA,0,0,10,0,30000"):
        p.result()
    client.sleep(0.3)
    status = client.status()
    assert status.moving and status.move.distance == 0.02
    client.stop()
    deadline = client.clock.now() + 10.0  # at once; late on a loaded machine's wall-clock backends
    while not rec.of(IdleEvent) and client.clock.now() < deadline:
        client.pump(0.05)
    client.sleep(0.05)
    assert len(rec.of(IdleEvent)) == 1
    status = client.status()
    assert (status.state, status.queued, status.powers) == (codes.STATE_IDLE, 0, (0, 0, 0, 0))
    assert (status.move.distance, status.move.speed) == (0.0, 0.0)  # STOP resets the remembered MOVE
    assert not client.moving


def test_emergency_stop_latch(backend: Backend) -> None:
    with backend.obstacle() as (link, stop_at), make_client(backend, link, owned=False) as client:
        rec = EventRecorder()
        client.add_listener(rec)
        client.sonar(1, 0.06, 0.0, 5.0, stop_at)
        client.move(math.inf, 0.6)
        client.wait_idle(timeout=30)
        warnings = rec.of(WarnEvent)
        # the guard may first slow the robot down (WARN 14, said once), then stops it
        assert [w.code for w in warnings] in ([codes.W_SONAR_STOP], [codes.W_SONAR_LIMIT, codes.W_SONAR_STOP])
        assert warnings[-1].text == codes.TEXTS[codes.W_SONAR_STOP]
        ranges = [r.distance for r in rec.of(RangeEvent) if r.time <= warnings[-1].time]
        assert ranges and all(d is not None and d <= stop_at + 0.3 for d in ranges)
        status = client.status()
        assert status.estop and status.powers == (0, 0, 0, 0)
        for blocked in (
            lambda: client.move(0.1, 0.4),
            lambda: client.rotate(1.0, 1.0),
            lambda: client.delta(repeat=1),
            lambda: client.power(0.1, [50, 50, 50, 50]),
            lambda: client.vel(0.1, 0.0, 0.0, 0.1),
        ):
            with pytest.raises(EmergencyStopLatched) as info:
                blocked()
            assert info.value.code == codes.E_ESTOP
        client.sonar(1, 0)
        assert client.status().estop  # still latched: only STOP releases it
        client.stop()
        assert client.status().idle
        client.move(0.05, 0.4)
        client.wait_idle(timeout=3)


def test_vel_watchdog_stops_silent_host(client: RobotClient) -> None:
    rec = EventRecorder()
    client.on_idle(rec)
    with ControllerClock(client) as clock:
        clock.command(lambda: client.vel(0.3, 0.0, 0.0, 0.2))
        assert any(client.status().powers)
        client.sleep(0.4)  # the host says nothing more
        deadline = client.clock.now() + 10.0  # (the IDLE may come late on a loaded machine)
        while not rec.of(IdleEvent) and client.clock.now() < deadline:
            client.pump(0.05)
        assert len(rec.of(IdleEvent)) == 1
        took = clock.until_idle()  # on the controller's clock: the watchdog's 0.2 s
    assert 0.15 <= took <= 0.35, took
    assert client.status().powers == (0, 0, 0, 0)


def test_vel_refreshed_keeps_running(client: RobotClient) -> None:
    """VELs of 1 s refreshed every 0.1 s for 2 s (twice the duration: one VEL alone would have
    ended) keep the robot going; then it stops once. The 0.9 s margin lets a loaded host be late, its
    VEL's round trip included (CI: the UNO went idle between two 0.2 s VELs sent 0.1 s apart, the pty
    emulator between two 0.5 s VELs at load 13)."""
    rec = EventRecorder()
    client.on_idle(rec)
    for _ in range(20):
        client.vel(0.0, 0.3, 0.0, 1.0)
        client.sleep(0.1)
    assert rec.events == [] and client.status().moving
    deadline = client.clock.now() + 10.0  # (the IDLE may come late on a loaded machine)
    while not rec.of(IdleEvent) and client.clock.now() < deadline:
        client.pump(0.05)
    client.sleep(0.2)
    assert len(rec.of(IdleEvent)) == 1


def test_open_loop_vel_sets_a_weak_wheel_to_0(client: RobotClient) -> None:
    """omni4's K_l tables were fitted from a dead band of about 44 PWM counts: 0.2 m/s forward with
    0.1 m/s sideways gives the sideways pair 41, which an open-loop VEL sets to 0 with WARN 12, once
    a VEL stream (every firmware: MicroPython and the UNO's); the closed loop drives them instead."""
    rec = EventRecorder()
    client.add_listener(rec, WarnEvent)
    client.vel(0.2, 0.1, 0.0, 1.0)  # the longest a VEL stays in force: a STATUS may come late under load
    client.vel(0.2, 0.1, 0.0, 1.0)
    assert client.status().powers == (0, 82, 0, -82)
    assert [w.code for w in rec.of(WarnEvent)] == [codes.W_POWER_TOO_LOW]
    client.stop()
    client.mode(closed_loop=True)  # omni4 has motor encoders
    client.vel(0.2, 0.1, 0.0, 1.0)
    assert client.status().powers[0] > 0
    client.stop()
    assert len(rec.of(WarnEvent)) == 1


def test_simulation_mode_computes_but_applies_nothing(client: RobotClient) -> None:
    tel = EventRecorder()
    client.on_telemetry(tel)
    client.telemetry(0.02, codes.TEL_POWER | codes.TEL_ENCODERS)
    client.sleep(0.3)  # let wheels still turning from earlier tests come to rest
    tel.clear()
    client.sleep(0.05)
    client.mode(simulation=True)
    client.move(math.inf, 0.4)  # moving until STOP, however late this test runs on a loaded machine
    client.sleep(0.05)
    status = client.status()
    assert status.simulation and status.moving and any(status.powers)  # what it would apply
    client.sleep(0.2)
    client.stop()
    client.sleep(0.1)
    samples = tel.of(Telemetry)
    assert samples[-1].encoders == samples[0].encoders  # no power reached the motors
    assert any(any(s.powers or ()) for s in samples)  # TEL reports the computed powers
    client.mode(0)
    client.telemetry(0)


def test_closed_loop_rotation_turns_the_robot(client: RobotClient, backend: Backend) -> None:
    backend.require_physics("the heading comes from the simulated gyro of a moving body")
    tel = EventRecorder()
    client.on_telemetry(tel)
    client.mode(closed_loop=True)  # open loop, omni4's dead band and slip make it turn short
    client.telemetry(0.05, codes.TEL_HEADING)
    client.sleep(0.1)
    before = tel.of(Telemetry)[-1].heading
    client.rotate(math.radians(90), math.radians(180))
    client.wait_idle(timeout=3)
    client.sleep(0.3)
    after = tel.of(Telemetry)[-1].heading
    assert before is not None and after is not None
    assert abs(math.degrees(after - before) - 90) < 15
    client.mode(0)
