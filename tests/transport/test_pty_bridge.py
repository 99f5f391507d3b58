"""The pty bridge: a device served on a real pseudo-terminal, in real time, paced to the baud."""

from __future__ import annotations

import threading
import time
from collections.abc import Callable

import pytest
import serial

from omnibot import collector
from omnibot.errors import LinkError
from omnibot.transport import pty_bridge
from omnibot.transport.pty_bridge import SERVICE_PERIOD, PtyBridge, next_wake

from .fakes import EchoDevice


# Waits are for a condition, with deadlines generous for a loaded machine (the bridge is a thread
# of this process, which may not be scheduled for a while); they end as soon as it is met.
def read_line(port: serial.Serial, timeout: float = 10.0) -> bytes:
    port.timeout = timeout
    line = bytes(port.read_until(b"\n"))
    assert line.endswith(b"\n"), f"no line within {timeout} s: {line!r}"
    return line


def wait_until(condition: Callable[[], bool], timeout: float = 10.0) -> None:
    deadline = time.monotonic() + timeout
    while not condition():
        assert time.monotonic() < deadline, "condition not met in time"
        time.sleep(0.005)


def test_echo_through_pyserial() -> None:
    with PtyBridge(EchoDevice()) as bridge, serial.Serial(bridge.path, 115200) as port:
        port.write(b"MOVE,2,40,0,0\n")
        assert read_line(port) == b"MOVE,2,40,0,0\n"
    assert bridge.steps > 0
    assert bridge.error is None


def test_pacing_holds_the_baud_rate() -> None:
    n = 2304  # 0.2 s at 115200 baud in each direction (pipelined)
    device = EchoDevice(per_byte=True)
    with PtyBridge(device, baud=115200) as bridge, serial.Serial(bridge.path) as port:
        port.timeout = 30
        t0 = time.monotonic()
        port.write(b"x" * n)
        data = port.read(n)
        elapsed = time.monotonic() - t0
    assert data == b"x" * n
    assert elapsed >= 0.15, elapsed  # not faster than the line
    # and not slower, on the device's clock (the wall's says how busy the machine was): 11.5 bytes a
    # 1 ms tick, 16 at most after a late wake-up
    first, last = device.receive_times[0][0], device.receive_times[-1][0]
    assert n / 16 * 0.001 <= last - first <= 0.25, (first, last)  # 0.199 s measured


def test_host_closes_and_reopens_the_slave() -> None:
    device = EchoDevice()
    connects: list[float] = []
    with PtyBridge(device, on_connect=lambda: connects.append(device.time)) as bridge:
        with serial.Serial(bridge.path) as port:
            port.write(b"one\n")
            assert read_line(port) == b"one\n"
            port.write(b"unread\n")  # echoed after the host has gone, or just before: never read
        # where the echo goes depends on whether the bridge read "unread" before or after the host
        # closed (discarded, or written to the pty and flushed at the hang-up): either way not seen below
        wait_until(lambda: not bridge.connected and device.received.endswith(b"unread\n"))
        with serial.Serial(bridge.path) as port:
            port.write(b"two\n")
            assert read_line(port) == b"two\n"  # no stale "unread" first
        assert device.received == b"one\nunread\ntwo\n"
        assert len(connects) == 2


def test_run_in_foreground_until_event() -> None:
    stop = threading.Event()
    bridge = PtyBridge(EchoDevice())
    timer = threading.Timer(0.1, stop.set)
    timer.start()
    t0 = time.monotonic()
    bridge.run(stop)
    bridge.close()
    timer.join()
    assert 0.09 <= time.monotonic() - t0 < 10.0  # stopped by the event (the timer's thread may be late)
    assert bridge.steps > 0  # one per 1 ms tick due; how many depends on the machine's load
    with pytest.raises(LinkError, match="closed"):
        bridge.start()


class BrokenDevice(EchoDevice):
    def step(self) -> None:
        raise RuntimeError("boom")


def test_device_failure_surfaces_on_stop() -> None:
    bridge = PtyBridge(BrokenDevice()).start()
    wait_until(lambda: bridge.error is not None)
    with pytest.raises(LinkError, match="boom"):
        bridge.stop()
    bridge.stop()  # idempotent


def _starved(bridge: PtyBridge, wakes: list[float]) -> list[tuple[int, int]]:
    """Drive the bridge's loop by hand (never started: no thread, no real time), waking at each of
    ``wakes`` (s) with 20,000 bytes from the host waiting; (bytes to the device, to the host) each time."""
    try:
        bridge.connected = True
        bridge._begin(0.0)
        bridge._to_device += b"x" * 20_000
        seen = []
        for now in wakes:
            bridge._advance(now)
            seen.append((bridge.bytes_to_device, len(bridge._wire)))
        return seen
    finally:
        bridge.close()


def test_a_late_loop_catches_up_the_line_with_the_device() -> None:
    """A bridge that wakes every 10 ms (starved) still passes the line's 11,520 B/s both ways."""
    bridge = PtyBridge(EchoDevice(per_byte=True), baud=115200)
    seen = _starved(bridge, [k * 0.010 for k in range(1, 11)])
    for k, (to_device, to_host) in enumerate(seen, start=1):
        line = k * 0.010 * 11_520  # bytes the line carries in that time
        assert line - 16 <= to_device <= line + 16, (k, to_device)
        assert line - 2 * 16 <= to_host <= to_device, (k, to_host)  # echoed a tick later, same pace
    assert bridge.skipped_ticks == 0 and bridge.steps in (99, 100)  # ticks summed in floating point


def test_beyond_max_catch_up_the_time_is_skipped_not_raced() -> None:
    """Half a second behind (more than max_catch_up): the backlog is skipped, only the due tick runs."""
    bridge = PtyBridge(EchoDevice(per_byte=True), baud=115200, max_catch_up=0.1)
    ((to_device, _),) = _starved(bridge, [0.5])
    assert bridge.steps == 1 and bridge.skipped_ticks == 499
    assert to_device <= 16  # only the ticks stepped carry bytes: skipped time is lost to the line too


def test_unpaced_bridge_passes_everything_on_the_first_tick() -> None:
    bridge = PtyBridge(EchoDevice(per_byte=True), baud=0)
    ((to_device, to_host),) = _starved(bridge, [0.001])
    assert to_device == to_host == 20_000


def test_the_next_pass_is_a_period_later_but_not_before_a_tick_is_due() -> None:
    assert next_wake(1.0, 1.001, 0.004) == pytest.approx(1.004)
    assert next_wake(1.0, 1.010, 0.004) == 1.010  # nothing to step before then
    assert next_wake(1.0, 1.001, 0.0) == 1.001  # period 0: every tick


class _FakeTime:
    """Stands in for the bridge module's ``time``: sleeping advances the clock; ``stop`` is set once
    ``until`` s have passed, so the loop runs a fixed stretch of fake time with no real waiting."""

    def __init__(self, until: float, stop: threading.Event) -> None:
        self.now, self.until, self.stop, self.sleeps, self.last_pass = 0.0, until, stop, 0, 0.0

    def monotonic(self) -> float:
        return self.now

    def sleep(self, seconds: float) -> None:
        self.sleeps += 1
        self.last_pass = self.now
        self.now += seconds
        if self.now >= self.until:
            self.stop.set()


@pytest.mark.parametrize(("period", "passes"), [(SERVICE_PERIOD, round(1 / SERVICE_PERIOD)), (0.0, 1000)])
def test_the_loop_wakes_once_a_period_and_still_steps_every_tick(
    period: float, passes: int, monkeypatch: pytest.MonkeyPatch
) -> None:
    """One second of (fake) wall time: the loop wakes 250 times with a 4 ms period instead of 1,000
    times (what the process costs), and either way the device has stepped every tick due by its last
    pass (ms ticks 1 .. last pass), none skipped."""
    stop = threading.Event()
    clock = _FakeTime(1.0, stop)
    monkeypatch.setattr(pty_bridge, "time", clock)
    bridge = PtyBridge(EchoDevice(), period=period)
    try:
        bridge.run(stop)
    finally:
        bridge.close()
    assert abs(clock.sleeps - passes) <= 1
    assert abs(bridge.steps - round(clock.last_pass / 0.001)) <= 1 and bridge.skipped_ticks == 0
    assert bridge.steps >= 990


def test_a_negative_period_is_refused() -> None:
    with pytest.raises(ValueError, match="service period must be >= 0 s"):
        PtyBridge(EchoDevice(), period=-0.001)


def test_serving_ends_the_commands_start(monkeypatch: pytest.MonkeyPatch) -> None:
    """The loop releases the garbage collector a command's start held (:mod:`omnibot.collector`)."""
    released: list[int] = []
    monkeypatch.setattr(collector, "release", lambda: released.append(1))
    stop = threading.Event()
    stop.set()
    bridge = PtyBridge(EchoDevice())
    bridge.run(stop)
    bridge.close()
    assert released == [1]
