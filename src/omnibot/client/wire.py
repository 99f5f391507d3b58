r"""The two wire formats the client speaks: text lines and binary frames with ARQ (no I/O).

Both turn a command into bytes (``frame``) and received bytes into packets (``feed``), lazily, so
the client can stop at the reply that switches protocols and hand the rest over (``rest``)::

    TextWire:    command -> "MOVE,2,40,0,0\n"        bytes -> Packet(message, seq=0) | Malformed
                 tagged:  "MOVE,2,40,0,0#17*C3A1\n"  bytes -> Packet(message, seq=tag)  (0: untagged)
                 sequenced (MODE bit 5): the tag is a seq with retries, as binary's (arq.Sender)
    BinaryWire:  command -> frame (seq, SYNC, retry)  bytes -> Packet(message, seq, event) | Malformed
                 + ack(seq) for events, service(now_ms) for retransmissions (arq.Sender)

A binary controller that resets speaks text again and greets with ``HELLO,...\r\n``;
:class:`BinaryWire` spots that line between frames and reports it as a HELLO packet with
``event=True`` (the client then treats it as a reset and goes back to text).
"""

from __future__ import annotations

import re
from collections.abc import Iterator
from typing import Final

from omnibot.protocol import arq, binary, codes, text
from omnibot.protocol.binary import Packet
from omnibot.protocol.messages import Ack, Command, HelloReply, Malformed, Mode, Stop
from omnibot.protocol.messages import Hello as HelloCommand

_RESET_RE: Final = re.compile(rb"HELLO,(\d+),([^,\r\n\x00]+),(\d+)\r\n")
_TAIL_MAX = 300
SYNC = (Stop, HelloCommand, Mode)
"""Sequenced text: the commands a controller takes whatever tag it expected (binary: STOP and HELLO)."""


class TextWire:
    """The line protocol: commands end with LF. With ``tags`` each command carries ``#tag*check``
    (tags 1..9999 in turn) and the client matches replies by tag; untagged ones in order. With
    :meth:`sequence` on (MODE bit 5) the tags are sequence numbers with retries (arq.Sender; the
    controller answers a duplicate from its kept reply), as binary frames' seqs."""

    binary = False

    def __init__(self, tags: bool = False, last_tag: int = 0) -> None:
        self.tags = tags
        self._decoder = text.TextDecoder(require_check=True)  # every tagged command has a check
        self._last_tag = last_tag
        self.sender: arq.Sender | None = None
        """Sequenced text (MODE bit 5): tagged commands awaiting their reply, sent again until it comes."""

    @property
    def last_tag(self) -> int:
        """The tag given last (0: none yet): a wire that replaces this one goes on from it."""
        return self._last_tag

    def sequence(self, on: bool) -> None:
        """Start sequenced tags (a fresh sender from the next tag: its first command must be a
        sync one, STOP, HELLO or MODE) or stop them (what was pending is no longer sent again)."""
        self.sender = (
            arq.Sender(
                window=codes.TEXT_SEQ_WINDOW,
                retries=codes.HOST_RETRIES + codes.TEXT_HOST_EXTRA_RETRIES,
                fast=codes.RETRIES + codes.TEXT_HOST_EXTRA_RETRIES,
                max_timeout_ms=codes.HOST_RETRY_TIMEOUT_MAX_MS,
                first_seq=self._last_tag % codes.TEXT_SEQ_MAX + 1,
                top=codes.TEXT_SEQ_MAX,
            )
            if on
            else None
        )

    def ready(self) -> bool:
        """True if another command may be sent now (sequenced: the sender's window has room)."""
        return self.sender is None or self.sender.ready()

    def next_tag(self) -> int:
        """The next tag, 1..TAG_MAX in turn."""
        self._last_tag = self._last_tag % text.TAG_MAX + 1
        return self._last_tag

    def frame(self, command: Command, now_ms: int, tag: bool | None = None) -> tuple[int, bytes]:
        """(tag, bytes) of a command; tag 0: untagged. ``tag`` overrides :attr:`tags`."""
        if not (self.tags if tag is None else tag):
            return 0, text.encode(command)
        if self.sender is None:
            n = self.next_tag()
            return n, text.encode(command, tag=n)
        n = self._allocate(isinstance(command, SYNC))
        return self._track(n, text.encode(command, tag=n), now_ms)

    def frame_raw(self, chunk: bytes, now_ms: int = 0, sync: bool = False) -> tuple[int, bytes]:
        """(tag, bytes) of a command typed by hand (without its terminator): tagged if tags are on
        and it still fits in a command, else as it is (``sync``: it is STOP, HELLO or MODE)."""
        if self.tags and len(text.with_suffix(chunk, text.TAG_MAX)) <= codes.LINE_MAX:
            if self.sender is None:
                n = self.next_tag()
                return n, text.with_suffix(chunk, n) + codes.COMMAND_END
            n = self._allocate(sync)
            return self._track(n, text.with_suffix(chunk, n) + codes.COMMAND_END, now_ms)
        return 0, chunk + codes.COMMAND_END

    def _allocate(self, sync: bool) -> int:
        assert self.sender is not None
        self._last_tag, _ = self.sender.allocate(sync=sync)
        return self._last_tag

    def _track(self, tag: int, data: bytes, now_ms: int) -> tuple[int, bytes]:
        assert self.sender is not None
        self.sender.track(tag, data, now_ms)
        return tag, data

    def feed(self, data: bytes) -> Iterator[Packet | Malformed]:
        """Decode received bytes into tagged packets (tag 0: untagged) or Malformed lines."""
        for message, tag in self._decoder.feed_tagged(data):
            yield message if isinstance(message, Malformed) else Packet(message, tag or 0)

    def gather(self) -> tuple[bytes, int]:
        """(ends, most): the bytes that end a line, and how many more may come before the line is
        too long; until one of those nothing received can be decoded
        (:meth:`~omnibot.transport.Link.read_gathered`)."""
        return self._decoder.ends, self._decoder.room()

    def rest(self) -> bytes:
        """The bytes of an unfinished line, handed to the next wire when the protocol switches."""
        return self._decoder.rest()

    def service(self, now_ms: int) -> list[bytes]:
        """Commands to send again now (sequenced text only)."""
        return [] if self.sender is None else self.sender.poll(now_ms)

    def take_failed(self) -> list[int]:
        """Tags given up on or abandoned (sequenced text only)."""
        return [] if self.sender is None else self.sender.take_failed()


class BinaryWire:
    """Binary frames: sequence numbers, retries and SYNC for commands, in-order events with ACKs."""

    binary = True

    def __init__(self) -> None:
        self._decoder = binary.BinaryDecoder()
        self.sender = arq.Sender(  # the window every controller takes, until its HELLO
            window=codes.WINDOW_MIN,
            retries=codes.HOST_RETRIES,
            max_timeout_ms=codes.HOST_RETRY_TIMEOUT_MAX_MS,
        )
        self.receiver = arq.Receiver(window=codes.WINDOW)  # events: a controller sends at most this many
        self._tail = b""  # bytes since the last 0x00, to spot a reset HELLO line
        self._after_reset: bytes | None = None

    def ready(self) -> bool:
        """True if the send window has room for another command."""
        return self.sender.ready()

    def frame(self, command: Command, now_ms: int) -> tuple[int, bytes]:
        """Allocate a seq (STOP and HELLO with SYNC, abandoning what is pending), encode, track."""
        binary.encode(command, 1)  # raises ProtocolError before a seq is used up
        seq, sync = self.sender.allocate(sync=isinstance(command, Stop | HelloCommand))
        data = binary.encode(command, seq, sync=sync)
        self.sender.track(seq, data, now_ms)
        return seq, data

    def hello(self, reply: HelloReply) -> None:
        """A binary HELLO reply came: send up to the window the controller announced (at most ours)."""
        if reply.window:
            self.sender.window = min(reply.window, codes.WINDOW)

    def ack(self, seq: int) -> bytes:
        """The ACK frame for event ``seq``."""
        return binary.encode(Ack(), seq)

    def feed(self, data: bytes) -> Iterator[Packet | Malformed]:
        """Decode received bytes into packets or Malformed frames, watching for a reset's text HELLO line."""
        yield from self._decoder.feed(data)
        cut = data.rfind(b"\x00")
        self._tail = (data[cut + 1 :] if cut >= 0 else self._tail + data)[-_TAIL_MAX:]
        found = _RESET_RE.search(self._tail)
        if found:
            self._after_reset = self._tail[found.end() :]
            self._tail = b""
            hello = HelloReply(int(found[1]), found[2].decode("ascii", "replace"), int(found[3]))
            yield Packet(hello, 0, event=True)

    def gather(self) -> None:
        """None: every frame is acted on as it comes (an event's ACK)."""
        return None

    def rest(self) -> bytes:
        """The bytes not yet decoded for the next wire: after a reset, those that followed its HELLO line."""
        pending = self._decoder.rest()
        if self._after_reset is not None:
            pending, self._after_reset = self._after_reset, None
        return pending

    def service(self, now_ms: int) -> list[bytes]:
        """Frames to retransmit now."""
        return self.sender.poll(now_ms)

    def take_failed(self) -> list[int]:
        """Seqs given up on (after the retries) or abandoned by a SYNC frame."""
        return self.sender.take_failed()


Wire = TextWire | BinaryWire
