"""Binary codec: round trips, any split, resynchronisation after garbage, worked examples, sizes."""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from omnibot.errors import ProtocolError
from omnibot.protocol import binary, codes, frame, text
from omnibot.protocol import messages as m
from tests.protocol import strategies as s

Item = binary.Packet | m.Malformed


def decode_all(data: bytes) -> list[Item]:
    out: list[Item] = []
    while True:
        used, item = binary.decode(data)
        if used == 0:
            return out
        data = data[used:]
        if item is not None:
            out.append(item)


def chunked(data: bytes, size: int) -> list[Item]:
    dec = binary.BinaryDecoder()
    out: list[Item] = []
    for i in range(0, len(data), size):
        out.extend(dec.feed(data[i : i + size]))
    return out


packets = st.builds(
    binary.Packet,
    s.messages,
    seq=st.integers(0, 255),
    sync=st.booleans(),
    event=st.booleans(),
).map(lambda p: p if isinstance(p.message, m.ErrorReply) else binary.Packet(p.message, p.seq, p.sync))


@given(packets)
def test_round_trip(packet: binary.Packet) -> None:
    wire = binary.encode_packet(packet)
    assert binary.decode(wire) == (len(wire), packet)


@given(s.commands)
def test_binary_is_at_most_6_bytes_longer_than_text_for_commands(cmd: m.Command) -> None:
    assert len(binary.encode(cmd, 1)) <= len(text.encode(cmd)) + 6


@given(st.lists(packets, max_size=8))
def test_any_split(items: list[binary.Packet]) -> None:
    data = b"".join(map(binary.encode_packet, items))
    half = len(data) // 2
    dec = binary.BinaryDecoder()
    halves = [*dec.feed(data[:half]), *dec.feed(data[half:])]
    for got in (decode_all(data), chunked(data, max(1, len(data))), halves, chunked(data, 1)):
        assert got == items


@given(st.lists(st.tuples(st.binary(max_size=80), packets), min_size=1, max_size=6), st.integers(1, 40))
def test_garbage_between_frames_never_costs_a_frame(
    parts: list[tuple[bytes, binary.Packet]], size: int
) -> None:
    data = b"".join(g + binary.encode_packet(p) for g, p in parts)
    for got in (decode_all(data), chunked(data, size)):
        assert [x for x in got if isinstance(x, binary.Packet)] == [p for _, p in parts]
        assert all(isinstance(x, m.Malformed) for x in got if not isinstance(x, binary.Packet))


def test_every_single_byte_corruption_is_caught() -> None:
    ok = binary.encode(m.Ok(), 1)
    for wire in (binary.encode(m.Move(2, 40, 0, 0), 1), binary.encode(m.Vel(35, -20, 45, 100), 200)):
        for pos in range(1, len(wire) - 1):
            for value in range(256):
                if value == wire[pos]:
                    continue
                bad = wire[:pos] + bytes([value]) + wire[pos + 1 :]
                got = decode_all(bad + ok)
                assert [x for x in got if isinstance(x, binary.Packet)] == [binary.Packet(m.Ok(), 1)]


def test_worked_examples() -> None:
    # the hex in docs/protocol.md
    move = binary.encode(m.Move(2, 40, 0, 0), 1)
    assert move.hex(" ") == "00 06 0d 01 01 04 50 01 01 8b ea 93 cb 8b 00"
    assert frame.cobs_decode(move[1:-6]).hex(" ") == "0d 01 01 04 50 00 00"
    assert binary.encode(m.Ok(), 1).hex(" ") == "00 04 09 20 01 f0 cf d1 9b 84 00"
    assert binary.encode(m.Stop(), 2, sync=True).hex(" ") == "00 04 09 85 02 e6 fd b5 c8 80 00"
    assert binary.encode(m.Ack(), 7).hex(" ") == "00 04 09 1f 07 f9 d1 a7 96 8f 00"
    assert binary.encode(m.Hello((2,)), 1, sync=True).hex(" ") == "00 05 0a 8b 01 04 b0 b2 a6 93 89 00"
    assert (  # version 2, 4 motors, window 32 (zigzag 64 = 40), then the name
        binary.encode(m.HelloReply(2, "omni4", 4, 32), 1).hex(" ")
        == "00 0c 11 22 01 04 08 40 6f 6d 6e 69 34 89 a1 94 83 8f 00"
    )
    err = binary.encode(m.ErrorReply(23, "unknown command"), 3)
    assert err.hex(" ") == "00 14 19 21 03 2e 75 6e 6b 6e 6f 77 6e 20 63 6f 6d 6d 61 6e 64 95 e0 80 ce 84 00"


def test_header_fields() -> None:
    event = binary.encode(m.ErrorReply(36, "x"), 9, event=True)
    assert binary.decode(event)[1] == binary.Packet(m.ErrorReply(36, "x"), 9, event=True)
    assert binary.type_id(m.ErrorReply(1), event=True) == codes.ERROR_EVENT
    assert binary.type_id(m.ErrorReply(1)) == codes.ERROR
    assert binary.type_id(m.Warn(1), event=True) == codes.WARN
    reply = binary.decode(binary.encode(m.HelloReply(1, "omni4", 4, 8), 1))[1]
    assert reply == binary.Packet(m.HelloReply(1, "omni4", 4, 8), 1)


@pytest.mark.parametrize("window", [0, codes.WINDOW_MIN - 1, codes.WINDOW_LIMIT + 1])
def test_hello_reply_window_outside_the_protocol_is_malformed(window: int) -> None:
    data = frame.encode_message(codes.HELLO_REPLY, 1, [2, 4, window], b"omni4")
    got = binary.decode(data)[1]
    assert isinstance(got, m.Malformed) and "window" in got.reason


@pytest.mark.parametrize("name", [b"omni4", b"mecanum4", b"Q"])
def test_hello_reply_without_a_window_says_the_firmware_predates_the_host(name: bytes) -> None:
    """A frame of the HELLO reply as it was before the window (version, motors, name): the name's
    first letter is read as the window, which no controller may announce ("o" is -56), and the
    reason says what it is."""
    got = binary.decode(frame.encode_message(codes.HELLO_REPLY, 1, [2, 4], name))[1]
    assert isinstance(got, m.Malformed) and got.reason == m.HELLO_WITHOUT_WINDOW
    assert "no window field" in m.HELLO_WITHOUT_WINDOW and "\n" not in m.HELLO_WITHOUT_WINDOW


@pytest.mark.parametrize("window", [-1, -70])
def test_a_negative_window_that_is_no_letter_is_just_out_of_range(window: int) -> None:
    got = binary.decode(frame.encode_message(codes.HELLO_REPLY, 1, [2, 4, window], b"omni4"))[1]
    assert isinstance(got, m.Malformed) and got.reason == f"HELLO reply: window {window} outside 8..127"


def test_a_window_read_from_a_letter_is_told_by_the_text_name() -> None:
    """``b`` reads as window 49, which the protocol allows: only the name the controller gave in
    its text HELLO shows a frame from before the window."""
    got = binary.decode(frame.encode_message(codes.HELLO_REPLY, 1, [2, 4], b"bot"))[1]
    assert isinstance(got, binary.Packet) and got.message == m.HelloReply(2, "ot", 4, 49)
    assert m.predates_window(got.message, "bot")
    assert not m.predates_window(m.HelloReply(2, "bot", 4, 49), "bot")
    assert not m.predates_window(got.message, "pot")


@pytest.mark.parametrize(
    ("type_id", "ints", "code"),
    [
        (100, [], codes.E_UNKNOWN),
        (codes.MOVE, [1, 2, 3], codes.E_PARAM_COUNT),
        (codes.POWER, [1, 2, 3, 4, 5, 6], codes.E_PARAM_COUNT),
        (codes.MOVE, [1, 2, 3, 40000], codes.E_RANGE16),
        (codes.RANGE, [1], codes.E_PARAM_COUNT),
    ],
)
def test_bad_messages_are_malformed(type_id: int, ints: list[int], code: int) -> None:
    _, got = binary.decode(frame.encode_message(type_id, 1, ints))
    assert isinstance(got, m.Malformed) and got.code == code


def test_bad_payloads_are_malformed() -> None:
    for wire in (
        frame.encode_frame(codes.MOVE, 1, b"\x80"),  # truncated varint
        frame.encode_frame(codes.ERROR, 1, b"\x2e\xff"),  # text not ASCII
    ):
        got = binary.decode(wire)[1]
        assert isinstance(got, m.Malformed) and got.reason == "bad payload"
        assert got.code == codes.E_NOT_INTEGER


def test_encode_rejects_what_binary_cannot_carry() -> None:
    for bad in (
        m.Move(32768, 0, 0, 0),
        m.Power(1, (1, 2, 3, 4, 5)),
        m.Warn(1, "caf\u00e9"),
        m.Telemetry(2**35),
        m.Telemetry(1, encoders=(2**31,) * 60),
    ):
        with pytest.raises(ProtocolError):
            binary.encode(bad)


def test_rest_hands_text_back_after_a_switch() -> None:
    dec = binary.BinaryDecoder()
    it = dec.feed(binary.encode(m.Ok(), 4) + b"HELLO,1,omni4,4\r\n")
    assert next(it) == binary.Packet(m.Ok(), 4)
    assert dec.rest() == b"HELLO,1,omni4,4\r\n"


# Figures of docs/protocol.md, "Bandwidth": 115200 baud 8N1 carries 11520 bytes/s each way.
LINE = 11520
VEL = m.Vel(35, -20, 45, 100)
TEL_TYPICAL = m.Telemetry(
    3_600_000,
    powers=(120, -120, 118, -119),
    encoders=(123456, -123456, 654321, -654321),
    gyro_rate=-4512,
    heading=90123,
    battery_mv=7400,
    queue=(0, 2),
)
TEL_WORST = m.Telemetry(
    2**31 - 1,
    powers=(-255,) * 4,
    encoders=(-(2**31),) * 4,
    gyro_rate=-(2**31),
    heading=-(2**31),
    battery_mv=65535,
    queue=(3, 64),
)


def test_bandwidth_figures() -> None:
    sizes = {
        "move": len(binary.encode(m.Move(2, 40, 0, 0), 1)),
        "move_worst": len(binary.encode(m.Move(-30000, -100, -359, -99), 1)),
        "vel": len(binary.encode(VEL, 1)),
        "vel_worst": len(binary.encode(m.Vel(-32768, -32768, -32768, 1000), 1)),
        "ok": len(binary.encode(m.Ok(), 1)),
        "tel": len(binary.encode(TEL_TYPICAL)),
        "tel_worst": len(binary.encode(TEL_WORST)),
        "text_vel": len(text.encode(VEL)),
        "text_tel": len(text.encode(TEL_TYPICAL)),
    }
    assert sizes == {
        "move": 15,
        "move_worst": 20,
        "vel": 16,
        "vel_worst": 22,
        "ok": 11,
        "tel": 48,
        "tel_worst": 64,
        "text_vel": 18,
        "text_tel": 90,
    }
    assert TEL_TYPICAL.mask == 123
    # host -> controller: VEL at 100 Hz
    assert 100 * sizes["vel_worst"] <= 0.5 * LINE
    # controller -> host: an OK per VEL plus TEL, both at 100 Hz
    assert 100 * (sizes["ok"] + sizes["tel"]) == 5900 <= 0.52 * LINE
    assert 50 * sizes["tel_worst"] + 100 * sizes["ok"] <= 0.5 * LINE
    assert 100 * (4 + sizes["text_tel"]) > 0.5 * LINE  # the text protocol does not fit


def test_vel_carries_the_body_acceleration_as_three_more_varints() -> None:
    """Version 4: AX, AY, AW after T (3 bytes more for zeros, 5 for a typical plan, 9 at worst); a
    frame with 6 or 8 integers gets ERROR 24 as the text does."""
    v4 = m.Vel(35, -20, 45, 100, body=(140, -60, 200))
    frame_bytes = binary.encode(v4, 5)
    assert binary.decode(frame_bytes) == (len(frame_bytes), binary.Packet(v4, 5, False))
    assert len(frame_bytes) == len(binary.encode(m.Vel(35, -20, 45, 100), 5)) + 5 == 21
    assert len(binary.encode(m.Vel(35, -20, 45, 100, body=(0, 0, 0)), 5)) == 19
    assert len(binary.encode(m.Vel(-32768, -32768, -32768, 1000, body=(-32768,) * 3), 5)) == 31
    for ints in ((35, -20, 45, 100, 140, -60), (35, -20, 45, 100, 140, -60, 200, 1)):
        wire = frame.encode_frame(codes.VEL, 6, bytes(frame.pack_ints(ints)))
        _, got = binary.decode(wire)
        assert isinstance(got, m.Malformed) and got.code == codes.E_PARAM_COUNT


def test_vel_carries_the_planned_acceleration_only_when_there_is_one() -> None:
    with_a = binary.encode(m.Vel(80, 0, 0, 200, 140), 3)
    without = binary.encode(m.Vel(80, 0, 0, 200), 3)
    assert len(with_a) == len(without) + 2  # 140 zigzags to 280: two varint bytes
    assert without == binary.encode(m.Vel(80, 0, 0, 200, 0), 3)
    assert binary.decode(with_a) == (len(with_a), binary.Packet(m.Vel(80, 0, 0, 200, 140), 3, False))
    assert binary.decode(without) == (len(without), binary.Packet(m.Vel(80, 0, 0, 200), 3, False))
