"""The emulated RPLIDAR in lockstep: requests in, answers and paced scan nodes out."""

from __future__ import annotations

import math

import numpy as np
import pytest

from omnibot.errors import ConfigError
from omnibot.lidar.rplidar_codec import (
    Command,
    Descriptor,
    DeviceInfo,
    Health,
    Request,
    ResponseType,
    ScanNode,
    SendMode,
    decode_descriptor,
    decode_response,
    encode_request,
)
from omnibot.lidar.rplidar_device import A1, A2, RESET_TIME, RplidarDevice, model_named, revolution_nodes
from omnibot.scan import Scan
from omnibot.transport import LockstepLink


def ring(n: int, base: float = 1.0, scan_time: float = 0.1) -> Scan:
    """A counter-clockwise scan whose ray i reads base + i mm (ray 7 has no return)."""
    ranges = base + np.arange(n) / 1000.0
    ranges[7] = math.inf
    return Scan(0.0, 0.0, 2 * math.pi / n, ranges, 0.1, 12.0, scan_time=scan_time)


def request(link: LockstepLink, command: int, payload: bytes | None = None) -> None:
    link.write(encode_request(Request(command, payload)))


def read_exact(link: LockstepLink, n: int, timeout: float = 1.0) -> bytes:
    out = b""
    while len(out) < n:
        chunk = link.read(n - len(out), timeout=timeout)
        if not chunk:
            break
        out += chunk
    return out


def answer(link: LockstepLink) -> object:
    _, d = decode_descriptor(read_exact(link, 7))
    assert d is not None and d.mode == SendMode.SINGLE
    _, msg = decode_response(read_exact(link, d.length), d)
    return msg


def read_nodes(link: LockstepLink, count: int) -> list[ScanNode]:
    data = read_exact(link, 5 * count)
    d = Descriptor(5, SendMode.MULTIPLE, ResponseType.SCAN)
    return [decode_response(data[i : i + 5], d)[1] for i in range(0, len(data), 5)]  # type: ignore[misc]


def test_info_and_health() -> None:
    dev = RplidarDevice(A2, serial_number=bytes(16))
    link = LockstepLink(dev, baud=A2.baud)
    request(link, Command.GET_INFO)
    assert answer(link) == DeviceInfo(0x28, (1, 29), 5, bytes(16))
    dev.health = Health(1, 42)
    request(link, Command.GET_HEALTH)
    assert answer(link) == Health(1, 42)


def test_scan_streams_one_revolution_per_scan_at_the_sample_rate() -> None:
    dev = RplidarDevice(A1)
    link = LockstepLink(dev, baud=A1.baud)
    scan = ring(200)
    dev.feed(scan)
    dev.feed(ring(200, base=2.0))
    request(link, Command.SCAN)
    t0 = dev.time
    assert decode_descriptor(read_exact(link, 7))[1] == Descriptor(5, SendMode.MULTIPLE, ResponseType.SCAN)
    nodes = read_nodes(link, 400)
    # 400 nodes at 2000/s: 0.2 s of device time (plus the request, the descriptor and a few ticks on the line)
    assert dev.time - t0 == pytest.approx(0.2, abs=0.005)
    assert [n.start for n in nodes].count(True) == 2 and nodes[0].start and nodes[200].start
    first = nodes[:200]
    for k, node in enumerate(first):
        assert node.angle_q6 == round(k * 1.8 * 64)
        ray = (-k) % 200  # clockwise node k reads the counter-clockwise ray at -k * 1.8 degrees
        if ray == 7:
            assert (node.distance_q2, node.quality) == (0, 0)
        else:
            assert node.distance_q2 == round(scan.ranges[ray] * 4000) and node.quality == 15
    assert nodes[200].distance_q2 == 8000
    # nothing more to stream: the stream pauses until the next scan
    assert link.read(5, timeout=0.05) == b""


def test_stop_ends_the_stream_and_requests_wait_while_scanning() -> None:
    dev = RplidarDevice(A1)
    link = LockstepLink(dev, baud=A1.baud)
    for i in range(2):
        dev.feed(ring(200, base=1.0 + i))
    request(link, Command.SCAN)
    read_exact(link, 7 + 5 * 10)
    request(link, Command.GET_HEALTH)  # waits: the device is scanning
    request(link, Command.STOP)
    link.advance(0.01)
    tail = link.read(100000, timeout=0)
    assert not dev.scanning
    assert tail.endswith(bytes.fromhex("a5 5a 03 00 00 00 06 00 00 00"))  # then GET_HEALTH's answer
    assert link.read(10, timeout=0.05) == b""


def test_a1_motor_follows_dtr_and_a2_motor_follows_pwm() -> None:
    a1 = RplidarDevice(A1)
    assert a1.motor_running
    a1.set_dtr(True)
    assert not a1.motor_running
    a2 = RplidarDevice(A2)
    link = LockstepLink(a2, baud=A2.baud)
    assert not a2.motor_running
    a2.feed(ring(100, scan_time=0.025))
    request(link, Command.SCAN)
    read_exact(link, 7)
    assert link.read(5, timeout=0.05) == b""  # motor stopped: no nodes
    request(link, Command.SET_MOTOR_PWM, (660).to_bytes(2, "little"))
    assert len(read_exact(link, 500)) == 500 and a2.pwm == 660


def test_force_scan_streams_with_the_motor_stopped() -> None:
    dev = RplidarDevice(A1)
    dev.set_dtr(True)
    link = LockstepLink(dev, baud=A1.baud)
    dev.feed(ring(200))
    request(link, Command.FORCE_SCAN)
    assert len(read_exact(link, 7 + 50)) == 57


def test_bad_requests_are_discarded_without_answer() -> None:
    dev = RplidarDevice(A1)
    link = LockstepLink(dev, baud=A1.baud)
    request(link, 0x33)  # unknown
    bad = bytearray(encode_request(Request(Command.SET_MOTOR_PWM, b"\x10\x00")))
    bad[-1] ^= 1
    link.write(bytes(bad))
    assert link.read(1, timeout=0.1) == b""
    assert [r.command for r in dev.discarded] == [0x33, Command.SET_MOTOR_PWM] and dev.pwm == 0
    request(link, Command.GET_HEALTH)  # still answers what it knows
    assert answer(link) == Health(0, 0)


def test_reset_reboots_prints_a_banner_and_loses_requests_meanwhile() -> None:
    dev = RplidarDevice(A2)
    link = LockstepLink(dev, baud=A2.baud)
    request(link, Command.SET_MOTOR_PWM, (500).to_bytes(2, "little"))
    dev.feed(ring(100, scan_time=0.025))
    request(link, Command.SCAN)
    read_exact(link, 7 + 50)
    request(link, Command.RESET)
    request(link, Command.GET_INFO)  # lost: the device is rebooting
    link.advance(RESET_TIME * 2)
    out = link.read(100000, timeout=0)
    assert b"RP LIDAR" in out and not dev.scanning and dev.pwm == 0
    assert b"\xa5\x5a" not in out[out.index(b"RP LIDAR") :]
    request(link, Command.GET_HEALTH)
    assert answer(link) == Health(0, 0)


def test_revolution_nodes_honour_range_limits_intensities_and_clockwise_scans() -> None:
    ranges = np.array([0.05, 1.0, 20.0, 2.0])
    cw = Scan(0.0, 0.0, -math.pi / 2, ranges, 0.1, 12.0, intensities=np.array([10.0, 99.0, 5.0, 30.4]))
    nodes = revolution_nodes(cw, 4)
    # a clockwise scan: node k reads ray k
    assert [(n.distance_q2, n.quality) for n in nodes] == [(0, 0), (4000, 63), (0, 0), (8000, 30)]
    # one ray, 45 degrees clockwise, 22.5 degrees wide: only the node at 45 degrees reads it
    one = Scan(0.0, -math.pi / 4, math.pi / 8, np.array([3.0]), 0.1, 12.0)
    assert [n.distance_q2 for n in revolution_nodes(one, 8)] == [0, 12000] + [0] * 6


def test_models_and_line_capacity() -> None:
    assert model_named("rplidar_a2") is A2 and model_named("A1M8") is A1
    with pytest.raises(ConfigError, match="unknown RPLIDAR model"):
        model_named("s2")
    with pytest.raises(ConfigError, match="do not fit"):
        RplidarDevice(A1, sample_rate=4000)
