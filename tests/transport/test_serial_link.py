"""Serial links: pyserial loop://, a pty served by the bridge, errors, reopen."""

from __future__ import annotations

import threading
import time
from pathlib import Path

import pytest

from omnibot.errors import ConfigError, LinkError
from omnibot.transport import SerialLink, open_link
from omnibot.transport.pty_bridge import PtyBridge
from tests.client.fakes import FakeClock

from .fakes import EchoDevice


def test_loop_roundtrip_and_timeout() -> None:
    with SerialLink("loop://") as link:
        assert link.url == "serial://loop://?baud=115200"
        link.write(b"hello")
        assert link.read(3, timeout=1) == b"hel"
        assert link.read(timeout=1) == b"lo"
        t0 = time.monotonic()
        assert link.read(timeout=0.05) == b""
        assert time.monotonic() - t0 >= 0.04
        assert link.read(timeout=0) == b""


def test_open_failure_and_retry_window() -> None:
    with pytest.raises(LinkError, match="cannot open serial port /dev/omnibot-missing"):
        SerialLink("/dev/omnibot-missing")
    clock = FakeClock()  # the retry window on the link's clock, not on a loaded machine's wall clock
    with pytest.raises(LinkError):
        SerialLink("/dev/omnibot-missing", open_retry=0.2, retry_interval=0.05, clock=clock)
    assert clock.t == pytest.approx(0.2)  # tried at 0, 0.05, .. 0.2, then gave up


def test_bad_baud() -> None:
    with pytest.raises(ConfigError, match="baud"):
        SerialLink("loop://", baud=0)


def test_reopen_loop() -> None:
    with SerialLink("loop://") as link:
        link.write(b"stale")
        link.reopen()
        assert link.is_open
        assert link.read(timeout=0.01) == b""  # a fresh port


def test_pty_echo_via_url() -> None:
    with PtyBridge(EchoDevice()) as bridge, open_link(f"{bridge.path}?baud=115200") as link:
        assert isinstance(link, SerialLink)
        link.write(b"HELLO\n")
        data = b""
        while not data.endswith(b"\n"):
            chunk = link.read(timeout=10)  # the bridge's thread, late on a loaded machine
            assert chunk
            data += chunk
        assert data == b"HELLO\n"


def test_port_going_away_then_reopen_with_retry(tmp_path: Path) -> None:
    """Like a USB adapter unplugged and re-plugged: /dev/serial/by-id/... goes away and comes back."""
    port = tmp_path / "ttyROBOT"
    bridge = PtyBridge(EchoDevice()).start()
    port.symlink_to(bridge.path)
    link = SerialLink(str(port))
    try:
        bridge.stop()  # unplugged: master closed, slave dead
        port.unlink()
        with pytest.raises(LinkError, match="failed") as broke:
            link.read(timeout=1)
        assert not link.is_open
        with pytest.raises(LinkError) as again:  # the writer's thread next: why it broke, not "not open"
            link.write(b"x")
        assert str(again.value) == str(broke.value)
        with pytest.raises(LinkError, match="cannot open"):
            link.reopen(retry=0.1)
        assert not link.closed

        bridge = PtyBridge(EchoDevice()).start()  # plugged in again
        threading.Timer(0.1, port.symlink_to, args=(bridge.path,)).start()
        link.reopen(retry=20.0)  # ends when the timer's thread has run: late on a loaded machine
        link.write(b"back\n")
        data = b""
        while not data.endswith(b"\n"):
            chunk = link.read(timeout=10)
            assert chunk
            data += chunk
        assert data == b"back\n"
    finally:
        link.close()
        bridge.stop()
