"""One contract, every transport: each backend below is an echo peer behind a Link."""

from __future__ import annotations

import threading
import time
from collections.abc import Callable, Iterator
from contextlib import ExitStack

import pytest

from omnibot.errors import LinkError
from omnibot.transport import FaultLink, Link, LockstepLink, SerialLink, SpyLink, TcpLink, open_link
from omnibot.transport.pty_bridge import PtyBridge

from .fakes import EchoDevice, EchoServer


def _lockstep(stack: ExitStack) -> Link:
    return LockstepLink(EchoDevice())


def _lockstep_wrapped(stack: ExitStack) -> Link:
    return SpyLink(FaultLink(LockstepLink(EchoDevice()), seed=1), lambda event: None)


def _loop(stack: ExitStack) -> Link:
    return open_link("loop://")


def _pty(stack: ExitStack) -> Link:
    bridge = stack.enter_context(PtyBridge(EchoDevice()))
    return SerialLink(bridge.path)


def _tcp(stack: ExitStack) -> Link:
    server = stack.enter_context(EchoServer())
    return TcpLink("127.0.0.1", server.port)


BACKENDS: dict[str, Callable[[ExitStack], Link]] = {
    "lockstep": _lockstep,
    "lockstep-wrapped": _lockstep_wrapped,
    "loop": _loop,
    "pty": _pty,
    "tcp": _tcp,
}


@pytest.fixture(params=sorted(BACKENDS))
def link(request: pytest.FixtureRequest) -> Iterator[Link]:
    with ExitStack() as stack:
        link = BACKENDS[request.param](stack)
        stack.callback(link.close)
        yield link


def read_line(link: Link, timeout: float = 2.0) -> bytes:
    data = b""
    while not data.endswith(b"\n"):
        chunk = link.read(timeout=timeout)
        assert chunk, f"timed out after {data!r}"
        data += chunk
    return data


def test_echo_lines(link: Link) -> None:
    for text in (b"HELLO\n", b"MOVE,2,40,0,0;DELTA,0,0,10,0,36\n", bytes(range(32, 127)) + b"\n"):
        link.write(text)
        assert read_line(link) == text


def test_read_honours_max_bytes(link: Link) -> None:
    link.write(b"abcdef\n")
    link.clock.sleep(0.05)
    data = link.read(2, timeout=1)
    assert 1 <= len(data) <= 2
    rest = b""
    while not (data + rest).endswith(b"\n"):
        rest += link.read(timeout=1)
    assert data + rest == b"abcdef\n"


def test_timeout_returns_empty_after_the_timeout_on_the_links_clock(link: Link) -> None:
    t0 = link.clock.now()
    assert link.read(timeout=0.05) == b""
    assert 0.04 <= link.clock.now() - t0 < 1.0
    assert link.read(timeout=0) == b""


def test_clock_sleep(link: Link) -> None:
    t0 = link.clock.now()
    link.clock.sleep(0.02)
    assert link.clock.now() - t0 >= 0.019


def test_wall_clock_says_whether_time_runs_on_while_nobody_reads(link: Link) -> None:
    """The runtime's pacer slices its reads by it (a wake's latency) on the wall clock only."""
    t0 = link.clock.now()
    time.sleep(0.01)
    assert link.wall_clock is (link.clock.now() - t0 >= 0.009)


def test_close(link: Link) -> None:
    assert not link.closed
    assert link.url
    link.close()
    link.close()
    assert link.closed
    with pytest.raises(LinkError):
        link.write(b"x")
    with pytest.raises(LinkError):
        link.read(timeout=0)


def test_close_wakes_a_blocked_reader(link: Link) -> None:
    errors: list[BaseException] = []

    def reader() -> None:
        try:
            link.read(timeout=None)
        except LinkError as exc:
            errors.append(exc)

    thread = threading.Thread(target=reader)
    thread.start()
    time.sleep(0.05)
    link.close()
    thread.join(10.0)  # at once, but the thread may be late on a loaded machine
    assert not thread.is_alive()
    assert len(errors) == 1
