"""The Slamtec RPLIDAR (A1/A2) serial protocol as a pure codec, both directions: no I/O, no state.

Little-endian throughout. 8N1 at 115200 baud (A1) or 256000 baud (A2).

Host -> device, a request::

    +------+-----+                          a command without payload (cmd & 0x80 == 0)
    | 0xA5 | cmd |                          STOP 0x25, RESET 0x40, SCAN 0x20, FORCE_SCAN 0x21,
    +------+-----+                          GET_INFO 0x50, GET_HEALTH 0x52, GET_SAMPLERATE 0x59

    +------+-----+------+------------------+----------+   a command with payload (cmd & 0x80)
    | 0xA5 | cmd | size | payload (size B) | checksum |   SET_MOTOR_PWM 0xF0 (u16 pwm),
    +------+-----+------+------------------+----------+   EXPRESS_SCAN 0x82, GET_ACC_BOARD_FLAG 0xFF
    checksum = XOR of every byte before it, 0xA5 included

Device -> host, a response descriptor once per request, then its data responses::

    +------+------+----------------------------+-----------+------+
    | 0xA5 | 0x5A | length (30 bits) | mode (2) | type (u8) |        7 bytes; length and mode share a
    +------+------+----------------------------+-----------+------+  u32: mode in its top two bits
    mode 0: one data response of ``length`` bytes; mode 1: data responses of ``length`` bytes
    until STOP or RESET (a scan)

Data responses, by descriptor type::

    INFO 0x04 (20 B):   model u8 | firmware minor u8 | firmware major u8 | hardware u8 | serial 16 B
    HEALTH 0x06 (3 B):  status u8 (0 good, 1 warning, 2 error) | error code u16
    SAMPLERATE 0x15 (4 B): standard scan us/sample u16 | express scan us/sample u16
    ACC_BOARD_FLAG 0xFF (4 B): flags u32 (bit 0: motor speed set by SET_MOTOR_PWM)
    SCAN 0x81 (5 B), one measurement (node):

        byte 0: quality (6 bits) << 2 | not start (1 bit) << 1 | start (1 bit)
        byte 1: angle_q6 bits 6..0 << 1 | check bit (always 1)
        byte 2: angle_q6 bits 14..7
        bytes 3-4: distance_q2 (u16)

    angle_q6: degrees * 64, clockwise seen from above; distance_q2: mm * 4, 0 when there was no
    return; start: the first node of a new revolution.

The device answers nothing to STOP and RESET (after RESET it prints an ASCII start-up banner), and
discards a request it does not know or whose checksum is wrong (protocol manual, "request packets'
format"): the host times out. :func:`decode_request` reports such a request as a :class:`Request`
with ``valid`` False, so that the device can discard it and a test can see why.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass
from enum import IntEnum
from typing import Final

from omnibot.errors import ProtocolError

__all__ = [
    "DESCRIPTOR_SIZE",
    "NODE_SIZE",
    "SYNC",
    "SYNC2",
    "AccBoardFlag",
    "Command",
    "Descriptor",
    "DeviceInfo",
    "Health",
    "Request",
    "ResponseType",
    "SampleRate",
    "ScanNode",
    "SendMode",
    "decode_descriptor",
    "decode_node",
    "decode_request",
    "decode_response",
    "encode_acc_board_flag",
    "encode_descriptor",
    "encode_health",
    "encode_info",
    "encode_node",
    "encode_request",
    "encode_samplerate",
]

SYNC: Final = 0xA5
SYNC2: Final = 0x5A
HAS_PAYLOAD: Final = 0x80
DESCRIPTOR_SIZE: Final = 7
NODE_SIZE: Final = 5
MAX_LENGTH: Final = (1 << 30) - 1


class Command(IntEnum):
    """Request command bytes."""

    STOP = 0x25
    RESET = 0x40
    SCAN = 0x20
    FORCE_SCAN = 0x21
    GET_INFO = 0x50
    GET_HEALTH = 0x52
    GET_SAMPLERATE = 0x59
    EXPRESS_SCAN = 0x82
    SET_MOTOR_PWM = 0xF0
    GET_ACC_BOARD_FLAG = 0xFF


class ResponseType(IntEnum):
    """Descriptor data types."""

    INFO = 0x04
    HEALTH = 0x06
    SAMPLERATE = 0x15
    SCAN = 0x81
    EXPRESS_SCAN = 0x82
    ACC_BOARD_FLAG = 0xFF


class SendMode(IntEnum):
    """A descriptor's send mode."""

    SINGLE = 0
    MULTIPLE = 1


# -- host -> device ---------------------------------------------------------------------------


@dataclass(frozen=True)
class Request:
    """One request. ``payload`` is None for a command without payload (``cmd & 0x80 == 0``).
    ``valid`` is False for a decoded request with a wrong checksum."""

    command: int
    payload: bytes | None = None
    valid: bool = True


def _xor(data: bytes) -> int:
    check = 0
    for b in data:
        check ^= b
    return check


def encode_request(request: Request) -> bytes:
    """The bytes of ``request`` (a payload needs a command with bit 7 set, and at most 255 bytes)."""
    if not 0 <= request.command <= 0xFF:
        raise ProtocolError(f"an RPLIDAR command is one byte, not {request.command}")
    has_payload = bool(request.command & HAS_PAYLOAD)
    if (request.payload is not None) != has_payload:
        raise ProtocolError(
            f"RPLIDAR command 0x{request.command:02X} {'needs' if has_payload else 'takes no'} payload"
        )
    head = bytes((SYNC, request.command))
    if request.payload is None:
        return head
    if len(request.payload) > 0xFF:
        raise ProtocolError(f"an RPLIDAR payload is at most 255 bytes, not {len(request.payload)}")
    body = head + bytes((len(request.payload),)) + request.payload
    return body + bytes((_xor(body),))


def decode_request(buf: bytes) -> tuple[int, Request | None]:
    """The first request in ``buf``: (bytes used, Request or None if more bytes are needed).

    Bytes before a 0xA5 are skipped (counted in ``used``). A request whose checksum is wrong comes
    back with ``valid`` False; one with an unknown command comes back as it is (the device decides).
    """
    start = buf.find(SYNC)
    if start < 0:
        return len(buf), None
    if len(buf) < start + 2:
        return start, None
    command = buf[start + 1]
    if not command & HAS_PAYLOAD:
        return start + 2, Request(command)
    if len(buf) < start + 3:
        return start, None
    size = buf[start + 2]
    end = start + 3 + size + 1
    if len(buf) < end:
        return start, None
    payload = bytes(buf[start + 3 : end - 1])
    valid = _xor(bytes(buf[start : end - 1])) == buf[end - 1]
    return end, Request(command, payload, valid)


# -- device -> host ---------------------------------------------------------------------------


@dataclass(frozen=True)
class Descriptor:
    """A response descriptor: ``length`` bytes per data response, ``mode`` single or multiple."""

    length: int
    mode: SendMode
    type: int


@dataclass(frozen=True)
class DeviceInfo:
    """GET_INFO's answer."""

    model: int
    firmware: tuple[int, int]
    """(major, minor)."""
    hardware: int
    serial_number: bytes
    """16 bytes."""

    @property
    def serial_hex(self) -> str:
        """The serial number as Slamtec's tools print it (32 upper-case hex digits)."""
        return self.serial_number.hex().upper()


@dataclass(frozen=True)
class Health:
    """GET_HEALTH's answer: status 0 good, 1 warning, 2 error."""

    status: int
    error_code: int = 0


@dataclass(frozen=True)
class SampleRate:
    """GET_SAMPLERATE's answer: microseconds per sample in standard and express scans."""

    standard_us: int
    express_us: int


@dataclass(frozen=True)
class AccBoardFlag:
    """GET_ACC_BOARD_FLAG's answer (bit 0: the motor is driven by SET_MOTOR_PWM)."""

    flags: int


@dataclass(frozen=True)
class ScanNode:
    """One measurement of a standard scan, in the protocol's units."""

    start: bool
    """First node of a new revolution."""
    quality: int
    """Return strength, 0..63."""
    angle_q6: int
    """Clockwise degrees * 64, 0..32767."""
    distance_q2: int
    """mm * 4, 0..65535; 0: no return."""

    @property
    def angle_deg(self) -> float:
        """Clockwise degrees."""
        return self.angle_q6 / 64.0

    @property
    def distance_mm(self) -> float:
        """mm (0: no return)."""
        return self.distance_q2 / 4.0


Response = DeviceInfo | Health | SampleRate | AccBoardFlag | ScanNode | bytes
"""A decoded data response (``bytes`` for a type this codec does not parse)."""


def encode_descriptor(descriptor: Descriptor) -> bytes:
    """The 7 bytes of a response descriptor."""
    if not 0 <= descriptor.length <= MAX_LENGTH:
        raise ProtocolError(f"an RPLIDAR response length has 30 bits, not {descriptor.length}")
    word = descriptor.length | (int(descriptor.mode) << 30)
    return struct.pack("<BBIB", SYNC, SYNC2, word, descriptor.type)


def decode_descriptor(buf: bytes) -> tuple[int, Descriptor | None]:
    """The descriptor at the start of ``buf``: (7, Descriptor) or (0, None) if more bytes are needed.
    ProtocolError if ``buf`` does not start with 0xA5 0x5A or names a reserved send mode."""
    for i, want in enumerate((SYNC, SYNC2)[: len(buf)]):
        if buf[i] != want:
            raise ProtocolError(f"an RPLIDAR response descriptor starts A5 5A, not {bytes(buf[:2]).hex(' ')}")
    if len(buf) < DESCRIPTOR_SIZE:
        return 0, None
    _, _, word, kind = struct.unpack_from("<BBIB", buf)
    mode = word >> 30
    if mode not in (SendMode.SINGLE, SendMode.MULTIPLE):
        raise ProtocolError(f"RPLIDAR send mode {mode} is reserved")
    return DESCRIPTOR_SIZE, Descriptor(word & MAX_LENGTH, SendMode(mode), kind)


def encode_info(info: DeviceInfo) -> bytes:
    """GET_INFO's 20-byte data response."""
    if len(info.serial_number) != 16:
        raise ProtocolError(f"an RPLIDAR serial number has 16 bytes, not {len(info.serial_number)}")
    major, minor = info.firmware
    return bytes((info.model, minor, major, info.hardware)) + info.serial_number


def encode_health(health: Health) -> bytes:
    """GET_HEALTH's 3-byte data response."""
    return struct.pack("<BH", health.status, health.error_code)


def encode_samplerate(rate: SampleRate) -> bytes:
    """GET_SAMPLERATE's 4-byte data response."""
    return struct.pack("<HH", rate.standard_us, rate.express_us)


def encode_acc_board_flag(flag: AccBoardFlag) -> bytes:
    """GET_ACC_BOARD_FLAG's 4-byte data response."""
    return struct.pack("<I", flag.flags)


def encode_node(node: ScanNode) -> bytes:
    """The 5 bytes of one scan node."""
    if not 0 <= node.quality <= 63:
        raise ProtocolError(f"an RPLIDAR quality is 0..63, not {node.quality}")
    if not 0 <= node.angle_q6 <= 0x7FFF:
        raise ProtocolError(f"an RPLIDAR angle_q6 is 0..32767, not {node.angle_q6}")
    if not 0 <= node.distance_q2 <= 0xFFFF:
        raise ProtocolError(f"an RPLIDAR distance_q2 is 0..65535, not {node.distance_q2}")
    flags = (node.quality << 2) | (0b01 if node.start else 0b10)
    return struct.pack("<BHH", flags, (node.angle_q6 << 1) | 1, node.distance_q2)


def decode_node(buf: bytes) -> tuple[int, ScanNode | None]:
    """The scan node at the start of ``buf``: (5, ScanNode) or (0, None) if more bytes are needed.
    ProtocolError if its start flags agree or its check bit is 0 (the host should resynchronise)."""
    if len(buf) < NODE_SIZE:
        return 0, None
    flags, angle, distance = struct.unpack_from("<BHH", buf)
    start, not_start = flags & 1, (flags >> 1) & 1
    if start == not_start:
        raise ProtocolError(f"RPLIDAR scan node with start flag {start} and inverse start flag {not_start}")
    if not angle & 1:
        raise ProtocolError("RPLIDAR scan node with check bit 0")
    return NODE_SIZE, ScanNode(bool(start), flags >> 2, angle >> 1, distance)


_FIXED: dict[int, int] = {
    ResponseType.INFO: 20,
    ResponseType.HEALTH: 3,
    ResponseType.SAMPLERATE: 4,
    ResponseType.ACC_BOARD_FLAG: 4,
    ResponseType.SCAN: NODE_SIZE,
}


def decode_response(buf: bytes, descriptor: Descriptor) -> tuple[int, Response | None]:
    """One data response of the session ``descriptor`` opened: (bytes used, the response or None if
    more bytes are needed). A type this codec does not parse comes back as its raw bytes.
    ProtocolError if the descriptor's length does not fit its type."""
    kind, size = descriptor.type, descriptor.length
    if kind in _FIXED and size != _FIXED[kind]:
        raise ProtocolError(f"RPLIDAR response type 0x{kind:02X} has {_FIXED[kind]} bytes, not {size}")
    if len(buf) < size:
        return 0, None
    data = bytes(buf[:size])
    if kind == ResponseType.SCAN:
        return decode_node(data)
    if kind == ResponseType.INFO:
        return size, DeviceInfo(data[0], (data[2], data[1]), data[3], data[4:])
    if kind == ResponseType.HEALTH:
        status, code = struct.unpack("<BH", data)
        return size, Health(status, code)
    if kind == ResponseType.SAMPLERATE:
        return size, SampleRate(*struct.unpack("<HH", data))
    if kind == ResponseType.ACC_BOARD_FLAG:
        return size, AccBoardFlag(struct.unpack("<I", data)[0])
    return size, data
