"""The spy wrapper: events, hexdump format, timestamps on the link's clock."""

from __future__ import annotations

import io

import pytest

from omnibot.errors import LinkError
from omnibot.transport import LockstepLink, SpyEvent, SpyLink, open_link
from omnibot.transport.spy import format_event, hexdump

from .fakes import EchoDevice


def test_records_writes_and_reads_with_simulated_time() -> None:
    events: list[SpyEvent] = []
    with SpyLink(LockstepLink(EchoDevice(), baud=0), events.append) as link:
        link.write(b"HELLO\n")
        assert link.read(timeout=1) == b"HELLO\n"
        assert link.read(timeout=0.01) == b""  # not recorded without all_reads
    assert [(e.kind, e.data) for e in events] == [("TX", b"HELLO\n"), ("RX", b"HELLO\n"), ("CLOSE", b"")]
    assert events[0].time == 0.0
    assert events[1].time == pytest.approx(0.002)  # the echo's 2 ms latency, in device time


def test_all_reads_records_timeouts() -> None:
    events: list[SpyEvent] = []
    with SpyLink(LockstepLink(EchoDevice()), events.append, all_reads=True) as link:
        link.read(timeout=0.005)
    assert events[0] == SpyEvent(pytest.approx(0.005), "RX", b"")  # type: ignore[arg-type]
    assert format_event(events[0])[0].endswith("RX   <timeout>")


def test_text_trace_is_a_hexdump() -> None:
    out = io.StringIO()
    with SpyLink(LockstepLink(EchoDevice(), baud=0), out) as link:
        link.write(b"0123456789abcdefXYZ\r\n")
        link.read(timeout=0.01)
    lines = out.getvalue().splitlines()
    assert (
        lines[0]
        == "  0.000000 TX   0000  " + " ".join(f"{b:02X}" for b in b"0123456789abcdef") + "  0123456789abcdef"
    )
    assert lines[1].startswith("  0.000000 TX   0010  58 59 5A 0D 0A ")
    assert lines[1].endswith("  XYZ..")
    assert lines[-1].split() == ["0.002000", "CLOSE"]
    assert not out.closed  # not ours to close


def test_hexdump_rows() -> None:
    assert list(hexdump(b"")) == []
    (row,) = hexdump(b"A\x00")
    assert row == "0000  41 00" + " " * 42 + "  A."


def test_errors_are_recorded() -> None:
    events: list[SpyEvent] = []
    link = SpyLink(open_link("loop://"), events.append)
    link.inner.close()
    with pytest.raises(LinkError):
        link.write(b"x")
    assert [e.kind for e in events] == ["TX", "ERR"]
    assert "closed" in events[1].note
    link.close()
