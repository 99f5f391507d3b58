"""Reading a simulated link in tests: the bytes up to a marker, on the link's own clock."""

from __future__ import annotations

from omnibot.transport import Link


def read_until(link: Link, marker: bytes, timeout: float = 5.0) -> bytes:
    """Everything read from ``link`` until ``marker`` arrives or ``timeout`` s of its clock pass."""
    out = b""
    deadline = link.clock.now() + timeout
    while marker not in out and link.clock.now() < deadline:
        out += link.read(timeout=0.05)
    return out
