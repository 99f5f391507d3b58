"""Fault injection: reproducible by seed, rates as asked, delays on the link's clock."""

from __future__ import annotations

import pytest

from omnibot.transport import FaultLink, LockstepLink, open_link

from .fakes import EchoDevice

N = 20000
PAYLOAD = bytes(range(256)) * (N // 256) + bytes(N % 256)


def run_rx(seed: int, chunk: int = 1000, drop: float = 0.0, corrupt: float = 0.0) -> tuple[bytes, FaultLink]:
    """Send PAYLOAD through an unpaced echo device with faults on the receive side only."""
    inner = LockstepLink(EchoDevice(per_byte=True), baud=0)
    link = FaultLink(inner, drop=drop, corrupt=corrupt, seed=seed, direction="rx")
    received = bytearray()
    with link:
        for i in range(0, N, chunk):
            link.write(PAYLOAD[i : i + chunk])
        while data := link.read(timeout=0.01):
            received += data
    return bytes(received), link


def test_same_seed_same_faults_whatever_the_chunking() -> None:
    a, _ = run_rx(1, chunk=1000, drop=0.05, corrupt=0.05)
    b, _ = run_rx(1, chunk=37, drop=0.05, corrupt=0.05)
    c, _ = run_rx(2, chunk=1000, drop=0.05, corrupt=0.05)
    assert a == b
    assert a != c


@pytest.mark.parametrize(("drop", "corrupt"), [(0.01, 0.01), (0.1, 0.0), (0.0, 0.2)])
def test_rates_roughly_as_asked(drop: float, corrupt: float) -> None:
    received, link = run_rx(7, drop=drop, corrupt=corrupt)
    stats = link.stats
    assert stats.rx_bytes == N
    assert stats.tx_dropped == stats.tx_corrupted == 0
    assert len(received) == N - stats.rx_dropped
    # within 5 standard deviations of the binomial
    for count, p in ((stats.rx_dropped, drop), (stats.rx_corrupted, corrupt * (1 - drop))):
        assert abs(count - N * p) <= 5 * (N * p * (1 - p)) ** 0.5 + 1


def test_corruption_flips_one_bit() -> None:
    received, link = run_rx(3, corrupt=0.1)
    assert len(received) == N
    diffs = [a ^ b for a, b in zip(received, PAYLOAD, strict=True) if a != b]
    assert len(diffs) == link.stats.rx_corrupted
    assert all(d.bit_count() == 1 for d in diffs)


def test_no_faults_is_transparent() -> None:
    received, _ = run_rx(0)
    assert received == PAYLOAD


def test_tx_faults() -> None:
    device = EchoDevice(per_byte=True)
    with FaultLink(LockstepLink(device, baud=0), drop=0.5, direction="tx", seed=4) as link:
        link.write(bytes(1000))
        link.clock.sleep(0.01)
        assert len(device.received) == 1000 - link.stats.tx_dropped
        assert 400 < link.stats.tx_dropped < 600


def test_delay_in_simulated_time() -> None:
    device = EchoDevice()
    with FaultLink(LockstepLink(device, baud=0), delay=0.010, direction="tx") as link:
        link.write(b"ping\n")
        assert link.read(timeout=0.005) == b""  # still held back
        assert device.received == b""
        assert link.read(timeout=1) == b"ping\n"
        # 10 ms delay + 2 ms echo latency
        assert link.clock.now() == pytest.approx(0.012)


def test_delay_is_released_by_clock_sleep() -> None:
    device = EchoDevice()
    with FaultLink(LockstepLink(device, baud=0), delay=0.010) as link:
        link.write(b"x\n")
        link.clock.sleep(0.0095)
        assert device.received == b""
        link.clock.sleep(0.002)
        assert device.received == b"x\n"


def test_rx_delay_and_jitter_keep_order() -> None:
    with FaultLink(LockstepLink(EchoDevice(), baud=0), delay=0.005, jitter=0.005, direction="rx") as link:
        for i in range(20):
            link.write(f"{i}\n".encode())
        data = b""
        while chunk := link.read(timeout=0.05):
            data += chunk
    assert data == b"".join(f"{i}\n".encode() for i in range(20))


def test_wall_clock_delay_over_loop() -> None:
    with open_link("faults+loop://?delay_ms=30") as link:
        t0 = link.clock.now()
        link.write(b"abc")
        assert link.read(timeout=1.0) == b"abc"
        assert link.clock.now() - t0 >= 0.029


def test_wall_clock_is_the_wrapped_links() -> None:
    """The runtime's pacer slices its waits by it: over a wall-clock link a wake from another thread
    (ROS 2's cmd_vel) must not wait for a whole cycle because the wrapper has a clock of its own."""
    with (
        FaultLink(open_link("loop://"), delay=0.001) as wall,
        FaultLink(LockstepLink(EchoDevice())) as lockstep,
    ):
        assert wall.inner.wall_clock and wall.wall_clock
        assert not lockstep.inner.wall_clock and not lockstep.wall_clock


def test_bad_arguments() -> None:
    inner = LockstepLink(EchoDevice())
    with pytest.raises(ValueError, match="drop"):
        FaultLink(inner, drop=1.5)
    with pytest.raises(ValueError, match="delay"):
        FaultLink(inner, delay=-1)
    inner.close()


def test_any_positive_read_timeout_moves_lockstep_time() -> None:
    """A wait left over by float rounding (1e-17 s) still reads the inner link, which steps a tick:
    a caller looping until its deadline always sees time advance (RobotClient.sleep hung here)."""
    with FaultLink(LockstepLink(EchoDevice(), baud=0)) as link:
        before = link.clock.now()
        assert link.read(timeout=1e-17) == b""
        assert link.clock.now() > before


def test_zero_timeout_read_returns_what_has_arrived() -> None:
    with FaultLink(LockstepLink(EchoDevice(), baud=0)) as link:
        link.write(b"ping\n")
        link.clock.sleep(0.01)
        assert link.read(timeout=0) == b"ping\n"


@pytest.mark.parametrize("seconds", [0.05, 0.3])
def test_client_sleep_on_a_faults_link_ends(seconds: float) -> None:
    from omnibot.client import RobotClient

    with RobotClient.open("faults+sim://omni4?seed=1", settle=0) as client:
        start = client.clock.now()
        client.sleep(seconds)
        assert client.clock.now() == pytest.approx(start + seconds, abs=0.002)
