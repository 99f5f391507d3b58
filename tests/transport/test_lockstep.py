"""The in-process lockstep link: simulated time, UART pacing, determinism."""

from __future__ import annotations

import time

import pytest

from omnibot.errors import LinkError
from omnibot.transport import Clock, LockstepDevice, LockstepLink
from omnibot.transport.lockstep import PacedFifo

from .fakes import EchoDevice, QuietEcho


def read_exactly(link: LockstepLink, n: int, timeout: float = 5.0) -> bytes:
    data = b""
    while len(data) < n:
        chunk = link.read(n - len(data), timeout=timeout)
        assert chunk, f"timed out after {data!r}"
        data += chunk
    return data


def test_echo_device_satisfies_protocol() -> None:
    assert isinstance(EchoDevice(), LockstepDevice)


def test_echo_line_in_simulated_time() -> None:
    device = EchoDevice()
    with LockstepLink(device) as link:
        assert isinstance(link.clock, Clock)
        link.write(b"HELLO\n")
        assert read_exactly(link, 6) == b"HELLO\n"
        # 6 bytes out + 2 ms echo latency + 6 bytes back, each byte 86.8 us, in whole 1 ms ticks
        assert 0.003 <= link.clock.now() <= 0.006
    assert device.closed


def test_read_timeout_is_simulated_not_wall_clock() -> None:
    with LockstepLink(EchoDevice()) as link:
        t0 = time.monotonic()
        assert link.read(timeout=30.0) == b""
        # a wall-clock wait would take 30 s; the 30000 steps take a fraction of a second, a few on a
        # loaded machine
        assert time.monotonic() - t0 < 15.0
        assert link.clock.now() == pytest.approx(30.0)
        assert link.steps == 30000


def test_read_timeout_zero_does_not_step() -> None:
    with LockstepLink(EchoDevice()) as link:
        assert link.read(timeout=0) == b""
        assert link.steps == 0


def test_waits_round_up_to_whole_ticks() -> None:
    with LockstepLink(EchoDevice(tick=0.001)) as link:
        link.clock.sleep(0.0001)
        assert link.steps == 1
        link.clock.sleep(0.1)
        assert link.steps == 101
        link.advance(0)
        assert link.steps == 101


def test_clock_sleep_runs_device_and_buffers_output() -> None:
    with LockstepLink(EchoDevice()) as link:
        link.write(b"A\nB\n")
        link.clock.sleep(0.05)
        assert link.in_waiting == 4
        assert link.read(2, timeout=0) == b"A\n"
        assert link.read(timeout=0) == b"B\n"


def test_pacing_115200_in_both_directions() -> None:
    device = EchoDevice(per_byte=True)
    with LockstepLink(device, baud=115200) as link:
        link.write(bytes(1152))
        assert read_exactly(link, 1152) == bytes(1152)
        # 1152 bytes * 10 bits / 115200 = 0.1 s each way, pipelined through the echo
        assert 0.1 <= link.clock.now() <= 0.105
        last_delivery = device.receive_times[-1][0]
        assert last_delivery == pytest.approx(0.1, abs=0.0011)
        # no tick delivers more than the line carries in a tick (11.52 bytes per ms)
        assert max(n for _, n in device.receive_times) <= 12


def test_unpaced_is_one_tick() -> None:
    with LockstepLink(EchoDevice(per_byte=True), baud=0) as link:
        link.write(bytes(10000))
        assert read_exactly(link, 10000) == bytes(10000)
        assert link.clock.now() == pytest.approx(0.001)


def test_reads_return_partial_data_as_it_arrives() -> None:
    with LockstepLink(EchoDevice(per_byte=True), baud=9600) as link:
        link.write(b"x" * 100)
        first = link.read(timeout=1.0)
        assert 0 < len(first) < 100


def test_deterministic() -> None:
    def run() -> list[tuple[float, bytes]]:
        trace = []
        with LockstepLink(EchoDevice(), baud=57600) as link:
            for i in range(20):
                link.write(f"line {i}\n".encode())
                while chunk := link.read(timeout=0.003):
                    trace.append((link.clock.now(), chunk))
        return trace

    assert run() == run()


def test_closed_link_raises() -> None:
    link = LockstepLink(EchoDevice())
    link.close()
    link.close()  # idempotent
    assert link.closed
    with pytest.raises(LinkError, match="closed"):
        link.write(b"x")
    with pytest.raises(LinkError):
        link.read(timeout=0)
    with pytest.raises(LinkError):
        link.clock.sleep(0.1)


def test_cannot_reopen() -> None:
    with LockstepLink(EchoDevice()) as link, pytest.raises(LinkError, match="reopen"):
        link.reopen()


def test_bad_arguments() -> None:
    with LockstepLink(EchoDevice()) as link:
        with pytest.raises(ValueError, match="max_bytes"):
            link.read(0)
        with pytest.raises(ValueError, match="timeout"):
            link.read(timeout=-1)
        with pytest.raises(TypeError):
            link.write("text")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="tick"):
        LockstepLink(EchoDevice(tick=0))


def test_paced_fifo_queues_behind_busy_line() -> None:
    fifo = PacedFifo(byte_time=0.01)
    fifo.push(0.0, b"ab")
    fifo.push(0.005, b"c")  # line busy until 0.02: c is done at 0.03
    assert fifo.pop_due(0.009) == b""
    assert fifo.pop_due(0.01) == b"a"
    assert fifo.pop_due(0.029) == b"b"
    assert len(fifo) == 1
    assert fifo.pop_due(0.03) == b"c"
    fifo.push(1.0, b"d")  # idle line: starts at once
    assert fifo.pop_due(1.01) == b"d"


def test_paced_fifo_says_when_a_byte_arrives_and_where_an_end_is() -> None:
    fifo = PacedFifo(byte_time=0.01)
    fifo.push(0.0, b"ab")
    fifo.push(0.005, b"c\nd")  # behind the first two: c is in at 0.03, the LF at 0.04
    assert [fifo.arrival(n) for n in (1, 2, 3, 4, 5)] == pytest.approx([0.01, 0.02, 0.03, 0.04, 0.05])
    assert fifo.arrival(6) == float("inf")
    assert fifo.first_of(b"\r\n") == 3 and fifo.first_of(b"b") == 1 and fifo.first_of(b"x") == -1
    assert fifo.first_of(b"") == -1
    assert fifo.pop_due(0.02) == b"ab"
    assert fifo.arrival(2) == pytest.approx(0.04) and fifo.first_of(b"\n") == 1


def test_a_gathered_read_returns_at_an_end_at_more_than_most_or_at_its_timeout() -> None:
    with LockstepLink(EchoDevice(per_byte=True)) as link:  # 115200 baud: 11.52 bytes a 1 ms tick
        link.write(b"x" * 30 + b"\n" + b"y" * 100)
        got = link.read_gathered(b"\r\n", 256, timeout=1.0)
        assert got == b"x" * 30 + b"\n" + b"y" * (len(got) - 31) and len(got) < 31 + 12
        more = link.read_gathered(b"\n", 20, timeout=1.0)  # no end to come: 21 bytes and more
        assert 20 < len(more) < 21 + 12 and set(more) == {ord("y")}
        t0 = link.clock.now()
        rest = link.read_gathered(b"\n", 1000, timeout=0.002)  # the timeout first: what came by then
        assert 0 < len(rest) <= 24 and link.clock.now() == pytest.approx(t0 + 0.002)


def test_a_gathered_read_takes_what_is_there_when_it_is_already_gathered() -> None:
    with LockstepLink(EchoDevice()) as link:
        link.write(b"A\nB\n")
        link.clock.sleep(0.05)
        steps = link.steps
        assert link.read_gathered(b"\n", 256, timeout=1.0) == b"A\nB\n" and link.steps == steps
        assert link.read_gathered(b"\n", 256, timeout=0) == b"" and link.steps == steps


@pytest.mark.parametrize("baud", [57600, 115200, 115201, 300, 0])
@pytest.mark.parametrize("device", [EchoDevice, QuietEcho])
def test_reads_gathered_get_the_bytes_of_reads_by_the_same_times(baud: int, device: type[EchoDevice]) -> None:
    """Tick by tick or in quiet runs up to the tick a line's end arrives, at any baud rate."""

    def session(gather: bool) -> tuple[list[tuple[float, bytes]], int]:
        reads: list[tuple[float, bytes]] = []
        with LockstepLink(device(), baud=baud) as link:
            for i in range(20):
                link.write(f"line {i} of the session\n".encode())
                end = link.clock.now() + (2.0 if baud == 300 else 0.02)
                while (left := end - link.clock.now()) > 0:
                    chunk = (
                        link.read_gathered(b"\n", 256, timeout=left) if gather else link.read(timeout=left)
                    )
                    if chunk:
                        reads.append((link.clock.now(), chunk))
            return reads, link.steps

    plain, steps = session(False)
    gathered, gathered_steps = session(True)
    assert gathered_steps == steps and len(gathered) == 20 and (baud == 0 or len(gathered) < len(plain))
    ends = [t for t, chunk in plain if b"\n" in chunk]
    assert [t for t, _ in gathered] == ends
    for t, _ in gathered:
        assert b"".join(c for u, c in plain if u <= t) == b"".join(c for u, c in gathered if u <= t)
    assert b"".join(c for _, c in plain) == b"".join(c for _, c in gathered)
