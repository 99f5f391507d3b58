"""Scripted stand-ins for client tests: a link with a fake clock that answers what it is told to."""

from __future__ import annotations

from collections.abc import Callable

from omnibot.errors import LinkError
from omnibot.transport import Link


class FakeClock:
    """Time moves only when the link waits (a read that times out) or on sleep()."""

    def __init__(self) -> None:
        self.t = 0.0

    def now(self) -> float:
        return self.t

    def sleep(self, seconds: float) -> None:
        self.t += max(seconds, 0.0)


class ScriptedLink(Link):
    """A link whose peer is ``answer(line) -> bytes``, called for every LF-terminated line written.

    ``feed(data)`` queues bytes to be read; ``fail_reads`` makes the next reads raise LinkError
    (as a serial port that was unplugged), until :meth:`reopen`.
    """

    def __init__(self, answer: Callable[[bytes], bytes] | None = None) -> None:
        super().__init__("fake://scripted", FakeClock())
        self.answer = answer or (lambda line: b"")
        self.written = bytearray()
        self.inbox = bytearray()
        self._line = bytearray()
        self.fail_reads = 0
        self.broken = False
        self.reopens = 0

    def feed(self, data: bytes) -> None:
        self.inbox += data

    def _write(self, data: bytes) -> None:
        if self.broken:
            raise LinkError("fake link is broken")
        self.written += data
        for byte in data:
            self._line.append(byte)
            if byte == 0x0A:
                self.inbox += self.answer(bytes(self._line))
                self._line.clear()

    def _read(self, max_bytes: int, timeout: float | None) -> bytes:
        if self.fail_reads:
            self.fail_reads -= 1
            self.broken = True
            raise LinkError("fake link unplugged")
        if self.broken:
            raise LinkError("fake link is broken")
        if not self.inbox:
            self.clock.sleep(1.0 if timeout is None else timeout)
            return b""
        out = bytes(self.inbox[:max_bytes])
        del self.inbox[:max_bytes]
        return out

    def reopen(self, retry: float | None = None) -> None:
        self._check_open()
        self.reopens += 1
        self.broken = False

    def _close(self) -> None:
        pass


def controller(line: bytes) -> bytes:
    """A tiny text controller: OK to everything but STATUS, HELLO and FOO."""
    word = line.strip().split(b",")[0].upper()
    if word == b"STATUS":
        return b"STATUS,1,0,16,0;POWER,0,0,0,0;MOVE,0,0,0,0\r\n"
    if word == b"HELLO":
        return b"HELLO,1,fake,4\r\n"
    if word == b"FOO":
        return b"ERROR,23,unknown command\r\n"
    return b"OK\r\n"


class Silent:
    """A lockstep device that never answers."""

    tick = 0.001

    def __init__(self) -> None:
        self.time = 0.0

    def receive(self, data: bytes) -> None:
        pass

    def step(self) -> None:
        self.time += self.tick

    def transmit(self) -> bytes:
        return b""
