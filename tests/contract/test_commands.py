"""Every command's accepted path and the reply formats, on every backend."""

from __future__ import annotations

import itertools
import math
import re
import statistics

import pytest

from omnibot.client import (
    CalibrationRejected,
    EventRecorder,
    IdleEvent,
    NotSupported,
    OutOfRange,
    RobotClient,
    Telemetry,
)
from omnibot.protocol import codes, units
from omnibot.protocol.messages import Cal, Hello, Mode, Move, Status

from .conftest import ROBOT, UNO, Backend, ControllerClock, RawLink


def latest(backend: Backend) -> int:
    """The highest protocol version the backend's controller speaks (the UNO's: 2, docs/uno.md; the
    Mega's build of the same firmware speaks every version)."""
    return 2 if backend.name == UNO else codes.VERSIONS[-1]


def test_hello_format(raw: RawLink, backend: Backend) -> None:
    raw.write(b"HELLO\n")  # a bare HELLO: the version every host speaks
    assert raw.line() == f"HELLO,2,{ROBOT},4\r\n".encode()
    raw.write(b"hello,5,2,1\n")  # versions the host speaks: the highest shared one answers
    assert raw.line() == f"HELLO,2,{ROBOT},4\r\n".encode()
    raw.write(b"hello,2,3\n")
    assert raw.line() == f"HELLO,{min(latest(backend), 3)},{ROBOT},4\r\n".encode()
    raw.write(b"hello,2,3,4\n")
    assert raw.line() == f"HELLO,{latest(backend)},{ROBOT},4\r\n".encode()


def test_vel_with_the_body_acceleration(raw: RawLink, backend: Backend) -> None:
    """Version 4's VEL,VX,VY,W,T,AX,AY,AW runs on a controller of version 4 and gets ERROR 24 (more
    than 5 parameters) from the UNO, which speaks version 2: it never misreads the fields."""
    raw.write(b"VEL,30,0,45,100,140,-20,300\n")
    if latest(backend) >= codes.VEL_BODY_ACCEL_VERSION:
        assert raw.line() == b"OK\r\n"
    else:
        assert raw.line().startswith(b"ERROR,24,")
    raw.write(b"STOP\n")
    assert raw.line() == b"OK\r\n"


def test_hello_versions(client: RobotClient) -> None:
    hello = client.hello([2])
    assert (hello.version, hello.name, hello.motors) == (2, ROBOT, 4)
    with pytest.raises(NotSupported) as info:
        client.execute(Hello((1, 5)))
    assert info.value.code == codes.E_UNSUPPORTED


def test_status_format(raw: RawLink) -> None:
    raw.write(b"STATUS\n")
    assert raw.line() == b"STATUS,1,0,16,0;POWER,0,0,0,0;MOVE,0,0,0,0\r\n"
    raw.write(b"MOVE,30000,40,90,0\nSTATUS\n")
    ok, status = raw.replies(2)
    assert ok == b"OK\r\n"
    m = re.fullmatch(rb"STATUS,0,0,16,0;POWER,(-?\d+),(-?\d+),(-?\d+),(-?\d+);MOVE,30000,40,90,0\r\n", status)
    assert m, status
    assert any(int(p) != 0 for p in m.groups())
    raw.write(b"STOP\nSTATUS\n")
    assert raw.replies(2) == [b"OK\r\n", b"STATUS,1,0,16,0;POWER,0,0,0,0;MOVE,0,0,0,0\r\n"]


def test_move_runs_then_idle(client: RobotClient) -> None:
    rec = EventRecorder()
    client.add_listener(rec, IdleEvent)
    with ControllerClock(client) as clock:
        sent = clock.command(lambda: client.move(0.1, 0.4))  # 10 cm at 40 cm/s: 0.25 s
        assert sent == Move(10, 40, 0, 0)
        assert client.status().moving
        client.wait_idle(timeout=10)
        took = clock.until_idle()
    assert len(rec.events) == 1
    assert 0.2 <= took <= 0.6, took
    status = client.status()
    assert status.idle and status.powers == (0, 0, 0, 0)
    assert status.move.distance == 0.1 and status.move.speed == 0.4


def test_rotate(client: RobotClient) -> None:
    with ControllerClock(client) as clock:
        sent = clock.command(lambda: client.rotate(math.radians(45), math.radians(180)))
        assert sent.params() == (45, 180)  # type: ignore[attr-defined]
        assert client.status().moving
        client.wait_idle(timeout=10)
        assert 0.2 <= clock.until_idle() <= 0.7
    assert client.status().move.speed == 0.0  # ROTATE leaves the remembered MOVE alone


def test_delta_circle_and_remembered_move(client: RobotClient) -> None:
    with ControllerClock(client) as clock:
        clock.command(lambda: [p.result() for p in client.submit_text("MOVE,2,40,0,0;DELTA,0,0,10,0,3")])
        client.wait_idle(timeout=10)
        assert 0.15 <= clock.until_idle() <= 0.6  # 4 moves of 50 ms
    status = client.status()
    assert status.idle
    assert (status.move.distance, status.move.speed, round(math.degrees(status.move.course))) == (
        0.02,
        0.4,
        30,
    )


def test_infinite_move_ends_at_next_command(client: RobotClient) -> None:
    client.move(math.inf, 0.4)
    client.sleep(0.1)
    assert client.status().moving
    with ControllerClock(client) as clock:
        clock.command(lambda: client.move(0.1, 0.4))  # the endless MOVE stops at once, this one runs 0.25 s
        client.wait_idle(timeout=10)
        assert clock.until_idle() <= 0.6
    assert client.status().move.distance == 0.1


def test_power(client: RobotClient) -> None:
    client.power(0.2, [60, -60, 60, -60])
    assert client.status().powers == (60, -60, 60, -60)
    client.wait_idle(timeout=3)
    assert client.status().powers == (0, 0, 0, 0)


def test_mode_bits(client: RobotClient) -> None:
    client.mode(simulation=True)
    assert client.status().mode == codes.MODE_SIMULATION
    client.mode(closed_loop=True)  # omni4 has motor encoders
    status = client.status()
    assert status.simulation and status.closed_loop
    client.mode(0)
    assert client.status().mode == 0


def test_telemetry_stream(client: RobotClient, backend: Backend) -> None:
    """TEL every 50 ms on the controller's clock. The controller keeps an absolute schedule (a late
    sample does not delay the next): in lockstep each gap is the period to the millisecond; a
    controller on the host's real clock may be preempted on a loaded machine, so there each sample
    may be late by up to half a period and the schedule holds on average."""
    rec = EventRecorder()
    client.on_telemetry(rec)
    client.telemetry(0.05, codes.TEL_MASK)
    client.sleep(0.32)
    client.telemetry(0)
    samples = rec.of(Telemetry)
    assert len(samples) >= 4
    gaps = [b.controller_time - a.controller_time for a, b in itertools.pairwise(samples)]
    if backend.realtime:
        assert all(0.025 <= g <= 0.075 for g in gaps), gaps
        assert 0.045 <= statistics.fmean(gaps) <= 0.055, gaps
    else:
        assert all(0.045 <= g <= 0.055 for g in gaps), gaps
    tel = samples[-1]
    assert tel.powers == (0, 0, 0, 0)
    assert tel.encoders is not None and len(tel.encoders) == 4
    assert tel.tracking == ()
    assert tel.gyro_rate is not None and tel.heading is not None
    assert tel.battery is not None and 5.0 < tel.battery < 9.0
    assert (tel.state, tel.queued) == (codes.STATE_IDLE, 0)
    assert tel.ranges is not None and len(tel.ranges) == 1
    rec.clear()
    client.sleep(0.15)
    assert rec.events == []


def test_sonar_and_telem_settings(client: RobotClient) -> None:
    assert client.sonar(1, 0.1, 0.2, 3.0, 0.0).params() == (1, 100, 20, 300, 0)
    client.sonar(1, 0)
    assert client.telemetry(0.1, codes.TEL_POWER | codes.TEL_QUEUE).params() == (100, 65)
    client.telemetry(0)


def test_cal_upload(client: RobotClient) -> None:
    from omnibot.robot import load_robot

    spec = load_robot(ROBOT).calibration
    assert spec is not None
    sent = client.upload_calibration(spec)  # the robot's own values: changes nothing
    assert sent[0].params() == (codes.CAL_K, 0, 0, units.to_cal_k(spec.k))
    assert all(isinstance(c, Cal) for c in sent)


def test_cal_motor_speed_terms(client: RobotClient) -> None:
    """The motor map's speed terms (CAL table 7): motor i gets ``speed_i u_i`` more at rim speed
    ``u_i`` (m/s), never against its direction; a course beyond 90 degrees and a motor that does not
    exist are refused (ERROR 38)."""
    from omnibot.robot import MotorMapSpec, PiecewiseLinear, load_robot

    spec = load_robot(ROBOT).calibration
    assert spec is not None
    flat = PiecewiseLinear(x=(0.0,), y=(1.0,))
    mapped = spec.model_copy(
        update={"motors": MotorMapSpec(offset=(0.0,) * 4, gain=(flat,) * 4, speed=(0.0, 100.0, 0.0, -50.0))}
    )
    try:  # VELs in force for the longest 1 s (STOP ends them): a loaded machine may delay the STATUS
        client.vel(0.2, 0.0, 0.0, 1.0)
        base = client.status().powers
        client.stop()
        client.upload_calibration(mapped)
        client.vel(0.2, 0.0, 0.0, 1.0)
        got = client.status().powers
        client.stop()
        p = base[1]
        assert p > 40 and base == (0, p, 0, -p)
        assert got == (0, p + 20, 0, -(p - 10))  # rim speeds +0.2 and -0.2 m/s
        for bad in ((codes.CAL_SPEED, 4, 0, 10), (codes.CAL_SPEED, 0, 1, 10), (codes.CAL_KL + 1, -1, 91, 0)):
            with pytest.raises(CalibrationRejected):
                client.execute(Cal(*bad))
    finally:
        client.upload_calibration(spec)


def test_cal_reach_runs_a_faster_move_at_the_reach(raw: RawLink, backend: Backend) -> None:
    """The calibrated reach (CAL table 8): an open-loop MOVE asked faster than the reach on its
    folded course runs at the reach (its powers those of a MOVE asked at it) with WARN 18; the
    remembered MOVE keeps the speed asked. The UNO has no room for it (docs/uno.md): ERROR 38."""
    if backend.name == UNO:
        pytest.skip("the UNO's flash has no room for the calibrated reach (docs/uno.md): CAL 8 is ERROR 38")
    raw.write(b"MOVE,30000,60,0,0\nSTATUS\nSTOP\n")
    at_reach = raw.replies(3)[1].split(b";")[1]
    try:
        raw.write(b"CAL,8,0,0,60\nMOVE,30000,80,0,0\n")
        assert raw.replies(2) == [b"OK\r\n", b"OK\r\n"]
        warn = raw.line(events=True)
        while warn.startswith(b"TEL,"):
            warn = raw.line(events=True)
        assert warn == f"WARN,{codes.W_REACH},{codes.TEXTS[codes.W_REACH]}\r\n".encode()
        raw.write(b"STATUS\nSTOP\n")
        status = raw.line().split(b";")
        assert status[1] == at_reach and status[2] == b"MOVE,30000,80,0,0\r\n", status
        assert raw.line() == b"OK\r\n"
    finally:
        raw.write(b"CAL,8,0,0,0\n")  # no reach: the preset's
        assert raw.line() == b"OK\r\n"


def test_stop_when_idle_sends_no_idle(client: RobotClient) -> None:
    rec = EventRecorder()
    client.add_listener(rec)
    client.stop()
    client.sleep(0.1)
    assert rec.of(IdleEvent) == []


def test_pipelined_replies_match_in_order(client: RobotClient) -> None:
    pendings = [client.submit(c) for c in (Status(), Mode(0), Hello(), Status(), Move(0, 20, 0, 0))]
    replies = [type(p.result()).__name__ for p in pendings[:4]]
    assert replies == ["StatusReply", "Ok", "HelloReply", "StatusReply"]
    with pytest.raises(OutOfRange) as info:
        pendings[4].result()
    assert info.value.code == codes.E_SPEED


def test_binary_round_trip(client: RobotClient, backend: Backend) -> None:
    rec = EventRecorder()
    client.add_listener(rec)
    hello = client.use_binary()
    assert client.binary and (hello.version, hello.name) == (latest(backend), ROBOT)
    assert client.status().binary
    client.move(0.05, 0.4)
    client.wait_idle(timeout=3)  # IDLE arrives as an event frame, acknowledged
    assert rec.of(IdleEvent)
    with pytest.raises(OutOfRange):
        client.execute(Move(0, 20, 0, 0))
    client.telemetry(0.05, codes.TEL_POWER | codes.TEL_QUEUE)
    client.sleep(0.2)
    client.telemetry(0)
    assert len(rec.of(Telemetry)) >= 2
    client.use_text()
    assert not client.binary
    assert client.status().mode == 0
