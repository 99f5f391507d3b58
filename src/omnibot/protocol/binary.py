"""Binary codec (docs/protocol.md, "Binary protocol"): messages <-> frames, no I/O.

The frame layer (length, COBS, CRC-32, varints) is :mod:`omnibot.protocol.frame`, shared with the
firmware. A message travels as its type id and its ``params()`` as zigzag varints; ERROR, WARN and
the HELLO reply add their text after the integers::

    00 | COBS( L | S+type | seq | varint p1 ... varint pn | text ... ) | 5 check bytes | 00

    MOVE,2,40,0,0 seq 1:  00 | 06 0d 01 01 04 50 01 01 | 8b ea 93 cb 8b | 00     (15 bytes; text 14)
          COBS decoded:        0d 01 01 04 50 00 00
                               L=13, type 01, seq 01, 2 -> 04, 40 -> 50, 0 -> 00, 0 -> 00
    OK to seq 1:          00 | 04 09 20 01 | f0 cf d1 9b 84 | 00                     (11 bytes)

L is the frame's length between the delimiters; the check bytes carry the CRC-32 of the bytes
before them as sent, 7 bits a byte. seq: commands and events carry their own (1..255), a reply the
seq of the command it answers, an ACK the seq of the event it acknowledges, TEL 0.
:mod:`omnibot.protocol.arq` runs the retries.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass

from omnibot.errors import ProtocolError
from omnibot.protocol import codes, frame
from omnibot.protocol.messages import (
    BY_TYPE,
    ErrorReply,
    Malformed,
    Message,
    check_command,
    is_command,
)

_VALUE_LIMIT = 1 << 34  # zigzag varints of at most 5 bytes


@dataclass(frozen=True)
class Packet:
    """A message with its frame header: ``seq``, ``sync`` and, for ErrorReply, ``event``
    (True when the motion logic raised it rather than a command being answered)."""

    message: Message
    seq: int = 0
    sync: bool = False
    event: bool = False


def type_id(message: Message, event: bool = False) -> int:
    """The binary type of a message (an ErrorReply event is ERROR_EVENT)."""
    if isinstance(message, ErrorReply) and event:
        return codes.ERROR_EVENT
    return message.TYPE


def encode(message: Message, seq: int = 0, *, sync: bool = False, event: bool = False) -> bytes:
    """One message as a complete frame; raises ProtocolError if it cannot be framed."""
    params = check_command(message) if is_command(message) else message.params()
    if any(not -_VALUE_LIMIT <= p < _VALUE_LIMIT for p in params):
        raise ProtocolError(f"{message.keyword}: a field is outside +-2**34")
    try:
        label = message.label().encode("ascii")
        return frame.encode_message(type_id(message, event), seq, params, label, sync)
    except (UnicodeEncodeError, ValueError) as exc:
        raise ProtocolError(f"{message.keyword}: {exc}") from exc


def encode_packet(packet: Packet) -> bytes:
    """:func:`encode` with the header fields of a Packet."""
    return encode(packet.message, packet.seq, sync=packet.sync, event=packet.event)


def from_frame(fr: frame.Frame) -> Packet | Malformed:
    """The Packet in a received frame, or Malformed (with the ERROR code a controller would use)."""
    if fr.error:
        return Malformed(fr.payload, fr.error)
    cls = BY_TYPE.get(fr.type_id)
    if cls is None:
        return Malformed(fr.payload, f"unknown message type {fr.type_id}", codes.E_UNKNOWN)
    try:
        params, label = fr.fields()
        text = label.decode("ascii")
    except (ValueError, UnicodeDecodeError):
        return Malformed(fr.payload, "bad payload", codes.E_NOT_INTEGER)
    if fr.type_id in codes.PARAM_COUNTS:
        if len(params) > codes.params_max(fr.type_id):
            return Malformed(fr.payload, "wrong number of parameters", codes.E_PARAM_COUNT)
        if any(not codes.INT_MIN <= p <= codes.INT_MAX for p in params):
            return Malformed(fr.payload, "value outside 16-bit range", codes.E_RANGE16)
    try:
        message = cls.from_params(params, text)
    except ProtocolError as exc:
        return Malformed(fr.payload, str(exc), codes.E_PARAM_COUNT)
    return Packet(message, fr.seq, fr.sync, fr.type_id == codes.ERROR_EVENT)


def decode(buf: bytes | bytearray) -> tuple[int, Packet | Malformed | None]:
    """Decode the first frame in ``buf``: (bytes used, Packet, Malformed or None for more bytes).

    Garbage between frames comes back as Malformed; the frame after it is intact.
    """
    used, fr = frame.decode(bytes(buf))
    return used, None if fr is None else from_frame(fr)


class BinaryDecoder:
    """Feed bytes, get packets: ``for p in dec.feed(chunk): ...`` (lazy, like TextDecoder)."""

    def __init__(self) -> None:
        self._buf = bytearray()
        self._frames = frame.FrameDecoder()

    def feed(self, data: bytes) -> Iterator[Packet | Malformed]:
        """Append ``data``; iterate over the packets (and Malformed chunks) now complete."""
        self._buf.extend(data)
        return self._drain()

    def _drain(self) -> Iterator[Packet | Malformed]:
        while self._buf:
            end = self._buf.find(frame.DELIMITER)
            chunk = bytes(self._buf) if end < 0 else bytes(self._buf[: end + 1])
            del self._buf[: len(chunk)]
            out: list[frame.Frame] = []
            self._frames.feed(chunk, out)
            for fr in out:
                yield from_frame(fr)

    def rest(self) -> bytes:
        """Take the bytes not decoded yet, with a partly received frame (e.g. text after a switch)."""
        out = self._frames.pending() + bytes(self._buf)
        self._buf.clear()
        self._frames.reset()
        return out
