"""The RPLIDAR codec: every frame whole, split and byte by byte, and against the rplidar driver's own
parsing (code we did not write: the independent side)."""

from __future__ import annotations

import pytest
import rplidar

from omnibot.errors import ProtocolError
from omnibot.lidar.rplidar_codec import (
    AccBoardFlag,
    Command,
    Descriptor,
    DeviceInfo,
    Health,
    Request,
    ResponseType,
    SampleRate,
    ScanNode,
    SendMode,
    decode_descriptor,
    decode_node,
    decode_request,
    decode_response,
    encode_acc_board_flag,
    encode_descriptor,
    encode_health,
    encode_info,
    encode_node,
    encode_request,
    encode_samplerate,
)

REQUESTS = [
    Request(Command.GET_INFO),
    Request(Command.SCAN),
    Request(Command.STOP),
    Request(Command.SET_MOTOR_PWM, (660).to_bytes(2, "little")),
    Request(Command.EXPRESS_SCAN, bytes(5)),
]


def chunks(data: bytes, mode: str) -> list[bytes]:
    if mode == "whole":
        return [data]
    if mode == "split":
        return [data[: len(data) // 2], data[len(data) // 2 :]]
    return [data[i : i + 1] for i in range(len(data))]


def decode_stream(parts: list[bytes], decode):
    buf, out = b"", []
    for part in parts:
        buf += part
        while True:
            used, msg = decode(buf)
            buf = buf[used:]
            if msg is None:
                break
            out.append(msg)
    return out, buf


@pytest.mark.parametrize("mode", ["whole", "split", "bytes"])
def test_requests_round_trip(mode: str) -> None:
    data = b"".join(encode_request(r) for r in REQUESTS)
    out, rest = decode_stream(chunks(data, mode), decode_request)
    assert out == REQUESTS and rest == b""


def test_request_bytes_are_what_the_driver_sends() -> None:
    sent: list[bytes] = []
    lidar = rplidar.RPLidar.__new__(rplidar.RPLidar)  # no port: only its request framing is used
    lidar._serial = type("W", (), {"write": lambda self, b: sent.append(b)})()
    lidar.logger = rplidar.logging.getLogger("test")
    lidar._send_cmd(rplidar.GET_HEALTH_BYTE)
    lidar._set_pwm(660)
    assert sent == [
        encode_request(Request(Command.GET_HEALTH)),
        encode_request(Request(Command.SET_MOTOR_PWM, (660).to_bytes(2, "little"))),
    ]
    assert sent[1] == bytes.fromhex("a5 f0 02 94 02") + bytes((0xA5 ^ 0xF0 ^ 0x02 ^ 0x94 ^ 0x02,))


def test_a_wrong_checksum_is_reported_not_raised() -> None:
    data = bytearray(encode_request(Request(Command.SET_MOTOR_PWM, b"\x00\x00")))
    data[-1] ^= 0xFF
    assert decode_request(bytes(data)) == (len(data), Request(Command.SET_MOTOR_PWM, b"\x00\x00", False))


def test_noise_before_a_request_is_skipped() -> None:
    assert decode_request(b"\x00\x13") == (2, None)
    assert decode_request(b"\x13\xa5") == (1, None)
    assert decode_request(b"\x13\xa5\x25") == (3, Request(Command.STOP))


def test_bad_requests_are_refused() -> None:
    with pytest.raises(ProtocolError, match="needs payload"):
        encode_request(Request(Command.SET_MOTOR_PWM))
    with pytest.raises(ProtocolError, match="takes no payload"):
        encode_request(Request(Command.STOP, b""))
    with pytest.raises(ProtocolError, match="255"):
        encode_request(Request(Command.EXPRESS_SCAN, bytes(256)))


INFO = DeviceInfo(0x18, (1, 29), 7, bytes.fromhex("00112233445566778899aabbccddeeff"))
RESPONSES = [
    (Descriptor(20, SendMode.SINGLE, ResponseType.INFO), encode_info(INFO), INFO),
    (
        Descriptor(3, SendMode.SINGLE, ResponseType.HEALTH),
        encode_health(Health(1, 0x1234)),
        Health(1, 0x1234),
    ),
    (
        Descriptor(4, SendMode.SINGLE, ResponseType.SAMPLERATE),
        encode_samplerate(SampleRate(500, 250)),
        SampleRate(500, 250),
    ),
    (
        Descriptor(4, SendMode.SINGLE, ResponseType.ACC_BOARD_FLAG),
        encode_acc_board_flag(AccBoardFlag(1)),
        AccBoardFlag(1),
    ),
]


@pytest.mark.parametrize("mode", ["whole", "split", "bytes"])
@pytest.mark.parametrize(("descriptor", "data", "message"), RESPONSES)
def test_responses_round_trip(mode: str, descriptor: Descriptor, data: bytes, message: object) -> None:
    wire = encode_descriptor(descriptor) + data
    buf, got = b"", []
    session: Descriptor | None = None
    for part in chunks(wire, mode):
        buf += part
        if session is None:
            used, session = decode_descriptor(buf)
            buf = buf[used:]
        if session is not None:
            used, msg = decode_response(buf, session)
            buf = buf[used:]
            if msg is not None:
                got.append(msg)
    assert session == descriptor and got == [message] and buf == b""


NODES = [
    ScanNode(True, 15, 0, 4000),
    ScanNode(False, 63, 359 * 64 + 63, 0xFFFF),
    ScanNode(False, 0, 12345, 0),
]


@pytest.mark.parametrize("mode", ["whole", "split", "bytes"])
def test_nodes_round_trip(mode: str) -> None:
    out, rest = decode_stream(chunks(b"".join(encode_node(n) for n in NODES), mode), decode_node)
    assert out == NODES and rest == b""


def test_nodes_read_by_the_driver() -> None:
    for node in NODES:
        assert rplidar._process_scan(encode_node(node)) == (
            node.start,
            node.quality,
            node.angle_deg,
            node.distance_mm,
        )


def test_info_and_descriptor_read_by_the_driver() -> None:
    d = Descriptor(5, SendMode.MULTIPLE, ResponseType.SCAN)
    fake = type("S", (), {"read": lambda self, n: encode_descriptor(d)})()
    lidar = rplidar.RPLidar.__new__(rplidar.RPLidar)
    lidar._serial, lidar.logger = fake, rplidar.logging.getLogger("test")
    assert lidar._read_descriptor() == (5, False, 0x81)
    raw = encode_info(INFO)
    assert (raw[0], (raw[2], raw[1]), raw[3]) == (INFO.model, INFO.firmware, INFO.hardware)
    assert raw[4:].hex().upper() == INFO.serial_hex


def test_health_error_code_byte_order() -> None:
    """The protocol puts error_code[7:0] first; the driver (rplidar 0.9.5) reads it the other way
    round, so a code only comes through that driver whole when its two bytes are equal."""
    raw = encode_health(Health(2, 0x1234))
    assert raw == bytes((2, 0x34, 0x12))
    assert (raw[1] << 8) + raw[2] == 0x3412  # what rplidar.RPLidar.get_health computes


def test_bad_responses_raise() -> None:
    with pytest.raises(ProtocolError, match="A5 5A"):
        decode_descriptor(b"\xa5\x5b")
    with pytest.raises(ProtocolError, match="reserved"):
        decode_descriptor(bytes((0xA5, 0x5A, 5, 0, 0, 0x80, 0x81)))
    with pytest.raises(ProtocolError, match="start flag"):
        decode_node(bytes((0b11, 1, 0, 0, 0)))
    with pytest.raises(ProtocolError, match="check bit"):
        decode_node(bytes((0b01, 0, 0, 0, 0)))
    with pytest.raises(ProtocolError, match="has 3 bytes"):
        decode_response(b"", Descriptor(4, SendMode.SINGLE, ResponseType.HEALTH))
    with pytest.raises(ProtocolError, match="quality"):
        encode_node(ScanNode(False, 64, 0, 0))
    assert decode_descriptor(b"\xa5") == (0, None)
    assert decode_response(b"\x01\x02", Descriptor(2, SendMode.SINGLE, 0x42)) == (2, b"\x01\x02")
