"""Binary frame layer: COBS framing, CRC-16, varint payloads (MicroPython-safe, bytes only).

Layout on the wire (docs/protocol.md, "Binary protocol")::

    0x00 | COBS( type | seq | payload ... | CRC hi | CRC lo ) | 0x00

    decoded frame, 4..254 bytes:
    +-+-------+--------+---------- ... ----------+--------+--------+
    |S| type  |  seq   | payload, 0..250 bytes    | CRC hi | CRC lo |
    +-+-------+--------+---------- ... ----------+--------+--------+
     bit 7 of the type byte (S) = SYNC: the sender abandoned every earlier frame
     seq: 1..255 (0 = unsequenced); CRC-16/CCITT-FALSE over type .. payload, big-endian
     payload: the message's integers as zigzag LEB128 varints, then (ERROR, WARN and the HELLO
     reply only, after codes.TEXT_AFTER[type] integers) ASCII text up to the CRC

COBS (Consistent Overhead Byte Stuffing) removes every 0x00 from the frame, so 0x00 only ever
delimits frames: a receiver that lost track drops bytes up to the next 0x00 and is in step again.
Each frame is sent between two delimiters, so garbage before a frame never spoils it; back-to-back
frames give empty frames between delimiters, which are skipped.

Plain functions and one small class; no typing, dataclasses or struct at run time, so the firmware
runs this very module on a board.
"""

from omnibot.protocol import codes
from omnibot.protocol.crc import crc16

DELIMITER = b"\x00"
MIN_SIZE = 4  # type, seq, CRC
ENCODED_MAX = codes.FRAME_MAX + 2  # COBS adds at most 2 bytes to a frame of <= 254 bytes
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
def encode_frame(type_id: int, seq: int, payload: bytes = b"", sync: bool = False) -> bytes:
    """A complete frame on the wire, delimiters included; raises ValueError if it does not fit."""
    if not 0 <= type_id <= codes.FRAME_TYPE_MASK or not 0 <= seq <= codes.SEQ_MAX:
        raise ValueError("type or seq out of range")
    raw = bytearray()
    raw.append((type_id | codes.FRAME_SYNC) if sync else type_id)
    raw.append(seq)
    raw.extend(payload)
    if len(raw) + 2 > codes.FRAME_MAX:
        raise ValueError("frame too long")
    crc = crc16(bytes(raw))
    raw.append(crc >> 8)
    raw.append(crc & 0xFF)
    return DELIMITER + cobs_encode(bytes(raw)) + DELIMITER


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
    """The frame in one COBS chunk (the bytes between two delimiters), or an error Frame."""
    if len(chunk) > ENCODED_MAX:
        return Frame(-1, 0, False, chunk[:ENCODED_MAX], "frame too long")
    try:
        raw = cobs_decode(chunk)
    except ValueError:
        return Frame(-1, 0, False, chunk, "bad COBS")
    if len(raw) < MIN_SIZE:
        return Frame(-1, 0, False, chunk, "frame too short")
    body = raw[:-2]
    if crc16(body) != (raw[-2] << 8) | raw[-1]:
        return Frame(-1, 0, False, chunk, "CRC mismatch")
    head = body[0]
    return Frame(head & codes.FRAME_TYPE_MASK, body[1], bool(head & codes.FRAME_SYNC), body[2:])


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
