"""Binary frame layer: length, COBS framing, CRC-32, varint payloads (MicroPython-safe, bytes only).

A frame on the wire (docs/protocol.md, "Frame"; protocol version 2)::

    00 | COBS( L | S+type | seq | payload ... ) | K0 K1 K2 K3 K4 | 00
         '--------- body: L - 5 bytes --------'  '- check, 5 -'

    L        the frame's length on the wire between its two 00 delimiters (9..255); never 00, so
             COBS copies it unchanged: it is always the frame's second byte
    S+type   bit 7 (S) = SYNC: the sender abandoned every earlier frame; bits 0-6 the message type
    seq      1..255 for commands, events, their replies and ACKs; 0 only in TEL
    payload  the message's integers as zigzag LEB128 varints, then (ERROR, WARN and the HELLO
             reply only, after codes.TEXT_AFTER[type] integers) ASCII text; 0..246 bytes
    K0..K4   CRC-32 of the body *as sent* (the COBS bytes, L included), 7 bits a byte, low bits
             first, bit 7 of each set so none is 00: K4 carries the top 4 bits (0x80..0x8F)

COBS (Consistent Overhead Byte Stuffing) removes every 00 from the body, so 00 only ever delimits
frames: garbage ends at the next 00 and the frame after it, which starts with its own 00, is intact.

What each part catches. The CRC covers exactly the bytes the wire carries between the delimiters
(check bytes aside), COBS code bytes included, so an error that leaves the delimiters in place is
an error of as many bits in the CRC's input and every one of 1 to 4 bits is detected (Hamming
distance 5 at these lengths, see :mod:`omnibot.protocol.crc`); a flipped bit 7 of a check byte is
seen at once. An error that cuts a frame (a byte lost, a byte turned into 00) or joins it to
what follows (a delimiter lost or changed) changes its length and no longer matches L, nor
usually the COBS block chain or the check bytes' bit 7; what is left for the CRC passes 1 time in
2^32. tests/protocol/test_frame_errors.py tries every 1- and 2-bit error, byte drop and truncation
of a frame set.

Plain functions and one small class; no typing, dataclasses or struct at run time, so the firmware
runs this very module on a board.
"""

from omnibot.protocol import codes
from omnibot.protocol.crc import crc32

DELIMITER = b"\x00"
CHECK_SIZE = 5  # CRC-32 in 5 bytes of 7 bits
OVERHEAD = 9  # COBS code byte, L, type, seq, check bytes
MIN_SIZE = OVERHEAD  # a frame without payload, delimiters excluded
ENCODED_MAX = codes.FRAME_MAX  # the longest frame between its delimiters
PAYLOAD_MAX = codes.FRAME_MAX - OVERHEAD
VARINT_BYTES_MAX = 5  # zigzag varints of up to 35 bits (signed 32-bit counters fit)


class Frame:
    """One received frame: ``type_id``, ``seq``, ``sync`` and ``payload`` bytes.

    A chunk that is not a frame has ``error`` set to the reason, ``type_id`` -1 and ``payload`` the
    raw bytes received (at most ENCODED_MAX of them).
    """

    def __init__(self, type_id: int, seq: int, sync: bool, payload: bytes, error: str = "") -> None:
        self.type_id = type_id
        self.seq = seq
        self.sync = sync
        self.payload = payload
        self.error = error

    def fields(self) -> "tuple[list[int], bytes]":
        """The payload as (integers, trailing text bytes); raises ValueError if it is malformed."""
        return unpack_fields(self.type_id, self.payload)


# --- COBS ----------------------------------------------------------------------------------------------
def cobs_encode(data: bytes) -> bytes:
    """COBS-encode ``data``: the result contains no 0x00 and is 1 byte longer per 254 bytes."""
    out = bytearray(1)
    code_at = 0
    code = 1
    for byte in data:
        if byte == 0:
            out[code_at] = code
            code_at = len(out)
            out.append(0)
            code = 1
        else:
            out.append(byte)
            code += 1
            if code == 0xFF:
                out[code_at] = code
                code_at = len(out)
                out.append(0)
                code = 1
    out[code_at] = code
    return bytes(out)


def cobs_decode(data: bytes) -> bytes:
    """Undo :func:`cobs_encode`; raises ValueError if ``data`` is not a COBS block sequence."""
    out = bytearray()
    i = 0
    n = len(data)
    while i < n:
        code = data[i]
        end = i + code
        if code == 0 or end > n:
            raise ValueError("bad COBS block")
        out.extend(data[i + 1 : end])
        i = end
        if code != 0xFF and i < n:
            out.append(0)
    return bytes(out)


# --- varint payloads ------------------------------------------------------------------------------
def pack_ints(values: "list[int] | tuple[int, ...]", out: "bytearray | None" = None) -> bytearray:
    """Append each integer as a zigzag LEB128 varint (0 -> 00, -1 -> 01, 1 -> 02, 64 -> 80 01)."""
    if out is None:
        out = bytearray()
    for v in values:
        z = v << 1 if v >= 0 else ((-v) << 1) - 1
        while z >= 0x80:
            out.append((z & 0x7F) | 0x80)
            z >>= 7
        out.append(z)
    return out


def unpack_ints(data: bytes, start: int = 0, count: int = -1) -> "tuple[list[int], int]":
    """Read ``count`` varints (all if -1) from ``data[start:]``: (values, index after the last).

    Raises ValueError on a truncated or over-long varint, or if fewer than ``count`` are there.
    """
    values: list[int] = []
    i = start
    n = len(data)
    while i < n and (count < 0 or len(values) < count):
        z = 0
        shift = 0
        while True:
            if i >= n or shift >= 7 * VARINT_BYTES_MAX:
                raise ValueError("bad varint")
            byte = data[i]
            i += 1
            z |= (byte & 0x7F) << shift
            shift += 7
            if byte < 0x80:
                break
        values.append(z >> 1 if not z & 1 else -((z + 1) >> 1))
    if count >= 0 and len(values) < count:
        raise ValueError("too few integers")
    return values, i


def pack_fields(type_id: int, ints: "list[int] | tuple[int, ...]", text: bytes = b"") -> bytes:
    """The payload of a message: its integers, then its text if its type carries one."""
    out = pack_ints(ints)
    if text:
        if type_id not in codes.TEXT_AFTER:
            raise ValueError("this message type carries no text")
        out.extend(text)
    return bytes(out)


def unpack_fields(type_id: int, payload: bytes) -> "tuple[list[int], bytes]":
    """Split a payload into (integers, text bytes) by its type."""
    n = codes.TEXT_AFTER.get(type_id, -1)
    ints, i = unpack_ints(payload, 0, n)
    return ints, payload[i:]


# --- frames -----------------------------------------------------------------------------------------
def check_bytes(crc: int) -> bytes:
    """The 5 check bytes of a CRC-32: 7 bits each, low bits first, bit 7 set (never 00)."""
    return bytes(
        (
            0x80 | (crc & 0x7F),
            0x80 | ((crc >> 7) & 0x7F),
            0x80 | ((crc >> 14) & 0x7F),
            0x80 | ((crc >> 21) & 0x7F),
            0x80 | (crc >> 28),
        )
    )


def check_value(data: bytes, start: int) -> int:
    """The CRC-32 in the 5 check bytes at ``data[start:]``, or -1 if they are not check bytes."""
    crc = 0
    shift = 0
    for i in range(start, start + CHECK_SIZE):
        byte = data[i]
        if byte < 0x80:
            return -1
        crc |= (byte & 0x7F) << shift
        shift += 7
    return -1 if crc >> 32 else crc


def encode_frame(type_id: int, seq: int, payload: bytes = b"", sync: bool = False) -> bytes:
    """A complete frame on the wire, delimiters included; raises ValueError if it does not fit."""
    if not 0 <= type_id <= codes.FRAME_TYPE_MASK or not 0 <= seq <= codes.SEQ_MAX:
        raise ValueError("type or seq out of range")
    size = len(payload) + OVERHEAD
    if size > codes.FRAME_MAX:
        raise ValueError("frame too long")
    raw = bytearray()
    raw.append(size)
    raw.append((type_id | codes.FRAME_SYNC) if sync else type_id)
    raw.append(seq)
    raw.extend(payload)
    body = cobs_encode(bytes(raw))  # len(raw) + 1 bytes: raw is shorter than one 254-byte block
    return DELIMITER + body + check_bytes(crc32(body)) + DELIMITER


def encode_message(
    type_id: int,
    seq: int,
    ints: "list[int] | tuple[int, ...]" = (),
    text: bytes = b"",
    sync: bool = False,
) -> bytes:
    """A frame carrying one message given as its integers and text."""
    return encode_frame(type_id, seq, pack_fields(type_id, ints, text), sync)


def parse_frame(chunk: bytes) -> Frame:
    """The frame in one chunk (the bytes between two delimiters), or an error Frame."""
    n = len(chunk)
    if n > ENCODED_MAX:
        return Frame(-1, 0, False, chunk[:ENCODED_MAX], "frame too long")
    if n < MIN_SIZE:
        return Frame(-1, 0, False, chunk, "frame too short")
    if chunk[1] != n:
        return Frame(-1, 0, False, chunk, "length mismatch")
    end = n - CHECK_SIZE
    crc = check_value(chunk, end)
    if crc < 0:
        return Frame(-1, 0, False, chunk, "bad check bytes")
    body = chunk[:end]
    if crc32(body) != crc:
        return Frame(-1, 0, False, chunk, "CRC mismatch")
    try:
        raw = cobs_decode(body)
    except ValueError:
        return Frame(-1, 0, False, chunk, "bad COBS")
    if len(raw) != end - 1 or raw[0] != n:
        return Frame(-1, 0, False, chunk, "length mismatch")
    head = raw[1]
    return Frame(head & codes.FRAME_TYPE_MASK, raw[2], bool(head & codes.FRAME_SYNC), raw[3:])


def decode(buf: bytes) -> "tuple[int, Frame | None]":
    """Decode the first frame in ``buf``: (bytes used, Frame or None if more bytes are needed).

    Leading delimiters are consumed. A chunk longer than a frame can be is consumed whole and
    reported as an error Frame even before its delimiter arrives.
    """
    n = len(buf)
    used = 0
    while used < n and buf[used] == 0:
        used += 1
    end = buf.find(DELIMITER, used)
    if end < 0:
        if n - used > ENCODED_MAX:
            return n, Frame(-1, 0, False, bytes(buf[used : used + ENCODED_MAX]), "frame too long")
        return used, None
    return end + 1, parse_frame(bytes(buf[used:end]))


class FrameDecoder:
    """Incremental decoder: ``feed(data, out)`` appends each frame (or error Frame) completed.

    An over-long chunk is reported once and dropped up to the next delimiter; at most ENCODED_MAX
    bytes are ever buffered.
    """

    def __init__(self) -> None:
        self._buf = bytearray()
        self._overflow = False

    def feed(self, data: bytes, out: "list[Frame]") -> None:
        """Consume ``data``; append the frames it completes to ``out``."""
        i = 0
        n = len(data)
        while i < n:
            end = data.find(DELIMITER, i)
            stop = n if end < 0 else end
            if not self._overflow:
                self._buf.extend(data[i:stop])
                if len(self._buf) > ENCODED_MAX:
                    out.append(Frame(-1, 0, False, bytes(self._buf[:ENCODED_MAX]), "frame too long"))
                    self._overflow = True
                    self._buf = bytearray()
            if end < 0:
                return
            if self._overflow:
                self._overflow = False
            elif self._buf:
                out.append(parse_frame(bytes(self._buf)))
                self._buf = bytearray()
            i = end + 1

    def reset(self) -> None:
        """Forget a partly received frame."""
        self._buf = bytearray()
        self._overflow = False

    def pending(self) -> bytes:
        """The bytes of the partly received frame."""
        return bytes(self._buf)
