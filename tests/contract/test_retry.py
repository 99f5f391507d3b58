"""Sequenced text (MODE bit 5): a command whose reply is lost is sent again and runs once.

The client's link is wrapped so that the reply to one tagged command is lost on its way back. The
controller answers the copy the client sends again from the reply it kept: the call succeeds, and
the DELTA, which adds to the remembered MOVE, ran once (twice, the MOVE would be 8 cm at 80 cm/s).
"""

from __future__ import annotations

from omnibot.client import RobotClient
from omnibot.protocol import codes
from omnibot.protocol.messages import Delta, Mode, Ok
from omnibot.transport import Link


class LosesAReply(Link):
    """``inner`` (left open on close), losing the first ``OK`` line tagged ``tag`` once armed."""

    def __init__(self, inner: Link) -> None:
        super().__init__(f"lose+{inner.url}", inner.clock)
        self.inner = inner
        self.tag: int | None = None
        self.lost = 0
        self.written: list[bytes] = []
        self._held = b""

    def _write(self, data: bytes) -> None:
        self.written.append(data)
        self.inner.write(data)

    def _read(self, max_bytes: int, timeout: float | None) -> bytes:
        data = self._held + self.inner.read(max_bytes, timeout)
        self._held = b""
        if self.tag is None or self.lost:
            return data
        out = b""
        while (end := data.find(b"\n")) >= 0:
            line, data = data[: end + 1], data[end + 1 :]
            if line.startswith(b"OK#%d*" % self.tag):
                self.lost += 1
                return out + data
            out += line
        self._held = data  # an unfinished line: looked at when the rest comes
        return out

    def _close(self) -> None:
        pass


def test_a_lost_reply_sent_again_runs_a_delta_once(client: RobotClient) -> None:
    client.execute(
        Mode(codes.MODE_CHECKED_TEXT | codes.MODE_SEQUENCED_TEXT)
    )  # the contract's reset cleared them
    assert client.sequenced and client.tags
    inner = client.link
    lossy = LosesAReply(inner)
    client.link = lossy
    try:
        pending = client.submit(Delta(4, 40, 0, 0, 0))  # the remembered MOVE (zeros) + 4 cm at 40 cm/s
        lossy.tag = pending.seq
        assert pending.result() == Ok()
        status = client.status()
    finally:
        client.link = inner
    assert lossy.lost == 1
    assert (
        sum(b"DELTA," in data for data in lossy.written) >= 2
    )  # sent again (more: sent before a reply came)
    move = status.move
    assert (round(move.distance, 3), round(move.speed, 3)) == (0.04, 0.4)  # once: twice is 8 cm at 80 cm/s
    client.wait_idle(timeout=5)
    client.execute(Mode(0))
