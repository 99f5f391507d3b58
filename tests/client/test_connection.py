"""The client's link (client/connection.py): bytes traced, a failure handed to the client, the link
reopened, or told again on the next call while it stays broken."""

from __future__ import annotations

import pytest

from omnibot.client.connection import Connection
from omnibot.errors import LinkError
from omnibot.protocol.messages import Malformed, Message
from tests.client.fakes import ScriptedLink


class Heard:
    """A tracer that keeps what it hears."""

    def __init__(self) -> None:
        self.bytes: list[tuple[str, bytes, str]] = []

    def link_bytes(self, t: float, kind: str, data: bytes = b"", note: str = "") -> None:
        self.bytes.append((kind, data, note))

    def message(self, t: float, direction: str, message: Message | Malformed) -> None:
        raise AssertionError("a connection hands tracers bytes only")


def test_the_bytes_go_through_and_the_tracers_hear_them() -> None:
    link = ScriptedLink(lambda line: b"OK\r\n")
    connection = Connection(link, 0.0, failed=lambda exc: pytest.fail(f"no failure expected: {exc}"))
    heard = Heard()
    connection.tracers.add(heard)
    connection.write(b"STOP\n")
    assert connection.read(0.1) == b"OK\r\n"
    assert connection.read(0.1) == b""  # nothing: not traced
    connection.close()
    connection.close()  # idempotent: CLOSE told once
    assert heard.bytes == [("TX", b"STOP\n", ""), ("RX", b"OK\r\n", ""), ("CLOSE", b"", "")]
    with pytest.raises(LinkError, match="is closed"):
        connection.ensure_open()


def test_a_failure_is_handed_to_the_client_and_the_link_reopened() -> None:
    link = ScriptedLink()
    failures: list[LinkError] = []
    connection = Connection(link, 0.0, failed=failures.append)
    heard = Heard()
    connection.tracers.add(heard)
    link.fail_reads = 1
    with pytest.raises(LinkError, match="unplugged"):
        connection.read(0.1)
    assert [str(f) for f in failures] == ["fake link unplugged"]
    assert heard.bytes == [("ERR", b"", "fake link unplugged")]
    assert link.reopens == 1 and not connection.broken  # reopened at once
    connection.ensure_open()
    assert link.reopens == 1


def test_without_reconnecting_the_link_stays_broken_and_the_next_call_says_why() -> None:
    link = ScriptedLink()
    link.broken = True
    connection = Connection(link, None, failed=lambda exc: None)
    with pytest.raises(LinkError, match="broken"):
        connection.write(b"STOP\n")
    assert connection.broken and link.reopens == 0
    with pytest.raises(LinkError, match="reconnecting is off \\(fake link is broken\\)"):
        connection.ensure_open()
    connection.reconnect = 0.0  # the client's reconnect, set later
    connection.ensure_open()
    assert link.reopens == 1 and not connection.broken
