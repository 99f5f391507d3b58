"""Text codec: round trips, any split of the stream, terminators, limits, bad input."""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from omnibot.errors import ProtocolError
from omnibot.protocol import codes, text
from omnibot.protocol import messages as m
from tests.protocol import strategies as s


def decode_all(data: bytes, commands: bool = False) -> list[object]:
    """Stateless decode over a whole buffer."""
    fn = text.decode_command if commands else text.decode
    out: list[object] = []
    while True:
        used, msg = fn(data)
        if used == 0:
            return out
        data = data[used:]
        if msg is not None:
            out.append(msg)


def chunked(data: bytes, size: int, commands: bool = False) -> list[object]:
    """TextDecoder fed ``size`` bytes at a time."""
    dec = text.TextDecoder(commands=commands)
    out: list[object] = []
    for i in range(0, len(data), size):
        out.extend(dec.feed(data[i : i + size]))
    return out


def splits(data: bytes, commands: bool = False) -> list[list[object]]:
    half = max(1, len(data) // 2)
    dec = text.TextDecoder(commands=commands)
    halves: list[object] = [*dec.feed(data[:half]), *dec.feed(data[half:])]
    return [
        decode_all(data, commands),
        chunked(data, len(data) or 1, commands),
        halves,
        chunked(data, 1, commands),
    ]


@given(s.commands)
def test_command_round_trip(cmd: m.Command) -> None:
    line = text.encode(cmd)
    assert line.endswith(b"\n") and line == line.upper()
    assert text.decode_command(line) == (len(line), cmd)
    assert text.decode_command(text.encode(cmd, b";")) == (len(line), cmd)


@given(s.text_host_bound)
def test_reply_and_event_round_trip(msg: m.Message) -> None:
    line = text.encode(msg)
    assert line.endswith(b"\r\n")
    assert text.decode(line) == (len(line), msg)


@given(st.lists(s.commands, max_size=8), st.sampled_from([b";", b"\n", b"\r\n", b";;\r\n"]))
def test_commands_any_split(cmds: list[m.Command], end: bytes) -> None:
    data = b"".join(text.encode(c, end) for c in cmds)
    for got in splits(data, commands=True):
        assert got == cmds


@given(st.lists(s.text_host_bound, max_size=8))
def test_replies_any_split(msgs: list[m.Message]) -> None:
    data = b"".join(text.encode(x) for x in msgs)
    for got in splits(data):
        assert got == msgs


def test_seed_example_two_commands_on_one_line() -> None:
    assert decode_all(b"MOVE,2,40,0,0;DELTA,0,0,10,0,36;", commands=True) == [
        m.Move(2, 40, 0, 0),
        m.Delta(0, 0, 10, 0, 36),
    ]


def test_terminator_runs_and_blank_commands_are_skipped() -> None:
    data = b";;\r\n\r\nstop\r\n;  ;status;;;hello,1\n\n"
    assert decode_all(data, commands=True) == [m.Stop(), m.Status(), m.Hello((1,))]
    assert text.decode_command(b";;;\r\n") == (5, None)
    assert text.decode_command(b"MOVE,1,") == (0, None)


def test_commands_are_case_insensitive_and_spaces_are_ignored() -> None:
    assert decode_all(b"mOvE , +2, 40 ,-0,0\r", commands=True) == [m.Move(2, 40, 0, 0)]


@pytest.mark.parametrize(
    ("line", "code"),
    [
        (b"JUMP,1", codes.E_UNKNOWN),
        (b",1", codes.E_UNKNOWN),
        (b"MOVE,1,2,3", codes.E_PARAM_COUNT),
        (b"STOP,1", codes.E_PARAM_COUNT),
        (b"POWER,1,2,3,4,5,6", codes.E_PARAM_COUNT),
        (b"VEL,1,2,3", codes.E_PARAM_COUNT),
        (b"VEL,1,2,3,4,5,6", codes.E_PARAM_COUNT),
        (b"VEL,1,2,3,4,x", codes.E_NOT_INTEGER),
        (b"VEL,1,2,3,4,", codes.E_NOT_INTEGER),
        (b"VEL,1,2,3,4,32768", codes.E_RANGE16),
        (b"MOVE,1,2,x,4", codes.E_NOT_INTEGER),
        (b"MOVE,1,2,,4", codes.E_NOT_INTEGER),
        (b"MOVE,1,2,3.5,4", codes.E_NOT_INTEGER),
        (b"MOVE,1_0,2,3,4", codes.E_NOT_INTEGER),
        (b"MOVE,1,2,3,32768", codes.E_RANGE16),
        (b"MOVE,1,2,3,-32769", codes.E_RANGE16),
        (b"MOVE," + b"1" * 60, codes.E_TOO_LONG),
    ],
)
def test_bad_commands_carry_their_error_code(line: bytes, code: int) -> None:
    used, msg = text.decode_command(line + b";STOP;")
    assert used == len(line) + 1
    assert isinstance(msg, m.Malformed) and msg.code == code and msg.raw == line
    assert text.decode_command((line + b";STOP;")[used:])[1] == m.Stop()


def test_command_limit_is_64_bytes_before_the_terminator() -> None:
    ok = b"POWER,1000," + b"0" * 53  # 64 bytes
    assert len(ok) == codes.LINE_MAX
    assert text.decode_command(ok + b";")[1] == m.Power(1000, (0,))
    assert text.decode_command(ok + b"0;")[1] == m.Malformed(ok + b"0", "command too long", 22)


def test_overlong_command_is_reported_once_and_dropped_to_the_terminator() -> None:
    data = b"MOVE," + b"9" * 200 + b",OK;STOP;"
    for size in (1, 7, len(data)):
        got = chunked(data, size, commands=True)
        assert len(got) == 2, size
        assert isinstance(got[0], m.Malformed) and got[0].code == codes.E_TOO_LONG
        assert got[1] == m.Stop()


def test_event_lines_may_be_longer_than_commands() -> None:
    tel = m.Telemetry(2**31, encoders=(-(2**31),) * 8, tracking=(2**31 - 1,) * 4, ranges=(500,) * 4)
    line = text.encode(tel)
    assert codes.LINE_MAX < len(line) <= codes.EVENT_LINE_MAX
    assert text.decode(line) == (len(line), tel)
    long_line = b"TEL,1,0" + b"," * 300 + b"\r\nIDLE\r\n"
    for size in (1, 50, len(long_line)):
        got = chunked(long_line, size)
        assert isinstance(got[0], m.Malformed) and got[0].reason == "line too long"
        assert got[1:] == [m.Idle()]


def test_status_reply_keeps_its_semicolons() -> None:
    line = b"STATUS,1,0,16,1;POWER,0,-10,20,0;MOVE,2,40,0,0\r\n"
    assert text.decode(line) == (len(line), m.StatusReply(1, 0, 16, 1, (0, -10, 20, 0), (2, 40, 0, 0)))
    assert (
        text.encode(m.StatusReply(3, 0, 8, 0, (), (0, 0, 0, 0))) == b"STATUS,3,0,8,0;POWER;MOVE,0,0,0,0\r\n"
    )


def test_host_direction_examples() -> None:
    data = (
        b"HELLO,1,omni4,4\r\nOK\r\nERROR,23,unknown command\r\nWARN,13,emergency stop by sonar\r\n"
        b"RANGE,1,35\r\nIDLE\r\nTEL,100,40,-5,7400\r\nERROR,36\r\nerror,36,a, b\r\n"
    )
    assert decode_all(data) == [
        m.HelloReply(1, "omni4", 4),
        m.Ok(),
        m.ErrorReply(23, "unknown command"),
        m.Warn(13, "emergency stop by sonar"),
        m.Range(1, 35),
        m.Idle(),
        m.Telemetry(100, gyro_rate=-5, battery_mv=7400),
        m.ErrorReply(36, ""),
        m.ErrorReply(36, "a, b"),
    ]


@pytest.mark.parametrize(
    "line",
    [
        b"HI",
        b"OK,1",
        b"ERROR",
        b"ERROR,x,text",
        b"HELLO,1,omni4",
        b"HELLO,1,,4",
        b"RANGE,1",
        b"TEL,1,8",
        b"STATUS,1,0,16,0",
        b"STATUS,1,0,16,0;MOVE,0,0,0,0;POWER,1",
        b"STATUS,1,0,16;POWER;MOVE,0,0,0,0",
        b"IDLE,\xff",
        b"\xc3\xa9",
    ],
)
def test_bad_lines_are_malformed(line: bytes) -> None:
    used, msg = text.decode(line + b"\r\nOK\r\n")
    assert used == len(line) + 2
    assert isinstance(msg, m.Malformed) and msg.raw == line


@given(st.binary(max_size=300), st.lists(s.text_host_bound, min_size=1, max_size=4))
def test_garbage_never_raises_and_whole_lines_after_it_survive(garbage: bytes, msgs: list[m.Message]) -> None:
    tail = b"".join(text.encode(x) for x in msgs)
    got = chunked(garbage + b"\r\n" + tail, 5)
    assert got[len(got) - len(msgs) :] == msgs


@given(st.binary(max_size=200))
def test_garbage_commands_never_raise(garbage: bytes) -> None:
    for msg in chunked(garbage + b";STOP;", 3, commands=True)[:-1]:
        assert isinstance(msg, m.Command | m.Malformed)


def test_encode_rejects_what_text_cannot_carry() -> None:
    for bad in (
        m.Move(32768, 0, 0, 0),
        m.Power(1, (1, 2, 3, 4, 5)),
        m.Ack(),
        m.HelloReply(1, "a,b", 4),
        m.HelloReply(1, "", 4),
        m.ErrorReply(1, "line\r\nbreak"),
        m.Warn(1, "caf\u00e9"),
        m.Telemetry(1, encoders=(2**40,) * 30),
    ):
        with pytest.raises(ProtocolError):
            text.encode(bad)


def test_empty_error_text_gets_the_standard_text() -> None:
    assert text.encode(m.ErrorReply(23)) == b"ERROR,23,unknown command\r\n"


def test_decoder_hands_over_the_rest_after_a_switch() -> None:
    dec = text.TextDecoder()
    it = dec.feed(b"OK\r\n\x00\x05\x20\x01\x0b\xc8\x00")
    assert next(it) == m.Ok()
    assert dec.rest() == b"\x00\x05\x20\x01\x0b\xc8\x00"
    assert list(it) == []


def test_decoder_left_mid_stream_still_gives_the_lines_it_holds() -> None:
    """Bytes without a terminator decode to nothing only when the buffer holds none either: a
    consumer that stopped early (the switch above, without taking the rest) gets the lines left."""
    dec = text.TextDecoder()
    it = dec.feed(b"OK\r\nIDLE\r\nWA")
    assert next(it) == m.Ok()
    assert list(dec.feed(b"RN,18,x")) == [m.Idle()]
    assert list(dec.feed(b"y")) == []
    assert list(dec.feed(b"\r\n")) == [m.Warn(18, "xy")]


def test_a_line_too_long_is_malformed_as_soon_as_it_is_past_the_limit() -> None:
    dec = text.TextDecoder()
    out: list[object] = []
    for k in range(codes.EVENT_LINE_MAX + 1):
        out.extend(dec.feed(b"A"))
        assert not out or k == codes.EVENT_LINE_MAX  # the byte past the limit: Malformed, not later
    assert len(out) == 1 and isinstance(out[0], m.Malformed)
    assert list(dec.feed(b"BBB")) == []  # the rest of that line is skipped
    assert list(dec.feed(b"\r\nOK\r\n")) == [m.Ok()]


# ------------------------------------------------------------------ tags, checks, INF, separators


def test_tagged_command_and_reply_round_trip() -> None:
    line = text.encode(m.Move(2, 40, 0, 0), tag=17)
    assert line == b"MOVE,2,40,0,0#17*9230\n"
    assert text.decode_command(line) == (len(line), m.Move(2, 40, 0, 0))
    reply = text.encode(m.Ok(), tag=17)
    assert reply == b"OK#17*BA98\r\n"
    assert text.decode_tagged(reply) == (len(reply), m.Ok(), 17)
    assert text.decode(reply) == (len(reply), m.Ok())
    assert text.decode_tagged(b"OK#5\r\n")[1:] == (m.Ok(), 5)  # a tag without a check
    status = text.encode(m.StatusReply(1, 0, 16, 0, (0, 0, 0, 0), (0, 0, 0, 0)), tag=9999)
    assert text.decode_tagged(status)[2] == 9999


def test_bad_check_is_malformed_both_ways() -> None:
    reply = bytearray(text.encode(m.Ok(), tag=17))
    reply[0] ^= 0x01  # "NK": the check no longer matches
    _, msg, tag = text.decode_tagged(bytes(reply))
    assert isinstance(msg, m.Malformed) and msg.reason == "checksum mismatch" and tag is None
    command = bytearray(text.encode(m.Move(2, 40, 0, 0), tag=3))
    command[5] = ord("3")
    bad = text.decode_command(bytes(command))[1]
    assert isinstance(bad, m.Malformed) and bad.code == codes.E_CHECKSUM


def test_every_command_fits_with_the_longest_tag() -> None:
    longest: list[m.Message] = [
        m.Delta(-32768, -32768, -32768, -32768, -32768),
        m.Power(-32768, (-32768,) * 4),
    ]
    for command in longest:
        assert len(text.encode(command, terminator=b"", tag=text.TAG_MAX)) <= codes.LINE_MAX
    with pytest.raises(ProtocolError, match="tag 10000 outside"):
        text.encode(m.Stop(), tag=10000)


@pytest.mark.parametrize(
    ("line", "code"),
    [
        (b"MOVE,\x0b1,40,0,0", codes.E_NOT_INTEGER),
        (b"MOVE,1\x0c,40,0,0", codes.E_NOT_INTEGER),
        (b"MOVE,1,40,0,\x850", codes.E_NOT_INTEGER),  # str.strip() would eat NEL
        (b"\x0b", codes.E_UNKNOWN),
        (b"MOVE,99999,x,0,0", codes.E_NOT_INTEGER),
        (b"MOVE,1,INF,0,0", codes.E_NOT_INTEGER),
    ],
)
def test_command_input_rules(line: bytes, code: int) -> None:
    msg = text.parse_command(line)
    assert isinstance(msg, m.Malformed) and msg.code == code


def test_inf_tokens() -> None:
    assert text.parse_command(b"MOVE,INF,60,0,0") == m.Move(30000, 60, 0, 0)
    assert text.parse_command(b"rotate,-inf,90") == m.Rotate(-30000, 90)
    assert text.parse_command(b"DELTA,0,0,10,0,Inf") == m.Delta(0, 0, 10, 0, 30000)


def test_a_client_decoder_takes_no_tagged_reply_without_its_check() -> None:
    """A line end moved in front of the ``*`` (a reordered byte) cuts the check off: the client, whose
    every tagged command carries one, must not take what is left for an answer."""
    strict, lenient = text.TextDecoder(require_check=True), text.TextDecoder()
    cut = b"OK#12\r\n"
    [(bad, tag)] = list(strict.feed_tagged(cut))
    assert isinstance(bad, m.Malformed) and bad.reason == "tagged reply without its check" and tag is None
    assert list(lenient.feed_tagged(cut)) == [(m.Ok(), 12)]  # a host that tags without checks
    whole = text.with_suffix(b"OK", 12) + b"\r\n"
    assert list(strict.feed_tagged(whole + b"OK\r\n")) == [(m.Ok(), 12), (m.Ok(), None)]


def test_vel_takes_the_planned_acceleration_as_an_optional_fifth_field() -> None:
    """Version 3's VEL,VX,VY,W,T,A; without A (or with A = 0) the command is version 2's, byte for
    byte, so a controller that does not know A reads what it always read."""
    assert text.decode_command(b"VEL,80,0,0,200,140\n")[1] == m.Vel(80, 0, 0, 200, 140)
    assert text.decode_command(b"VEL,80,0,0,200\n")[1] == m.Vel(80, 0, 0, 200)
    assert m.Vel(80, 0, 0, 200).accel == 0
    assert text.encode(m.Vel(80, 0, 0, 200, -140)) == b"VEL,80,0,0,200,-140\n"
    assert text.encode(m.Vel(80, 0, 0, 200, 0)) == b"VEL,80,0,0,200\n"


def test_vel_takes_the_body_acceleration_as_three_more_fields() -> None:
    """Version 4's VEL,VX,VY,W,T,AX,AY,AW (the one command with more than 5 parameters); zeros are
    sent (the plan says the body does not accelerate); 6 fields, or 8, are refused as a controller
    refuses them (ERROR 24), and the longest form with a tag and check fits the 64-byte limit."""
    v4 = m.Vel(35, -20, 45, 100, body=(140, -60, 200))
    assert text.encode(v4) == b"VEL,35,-20,45,100,140,-60,200\n"
    assert text.decode_command(b"VEL,35,-20,45,100,140,-60,200\n")[1] == v4
    assert text.encode(m.Vel(35, -20, 45, 100, body=(0, 0, 0))) == b"VEL,35,-20,45,100,0,0,0\n"
    for bad in (b"VEL,35,-20,45,100,140,-60", b"VEL,35,-20,45,100,140,-60,200,1", b"MOVE,1,2,3,4,5,6"):
        parsed = text.parse_command(bad)
        assert isinstance(parsed, m.Malformed) and parsed.code == codes.E_PARAM_COUNT
    worst = m.Vel(-32768, -32768, -32768, 1000, body=(-32768, -32768, -32768))
    assert len(text.with_suffix(text.encode(worst).rstrip(b"\n"), 9999)) <= codes.LINE_MAX
    with pytest.raises(ValueError, match="not both"):
        m.Vel(35, -20, 45, 100, 140, body=(140, 0, 0))
    with pytest.raises(ProtocolError, match="4, 5 or 7"):
        m.Vel.from_params((35, -20, 45, 100, 140, -60))


@pytest.mark.parametrize(
    ("fields", "expected"),
    [
        (["1", " -2 ", "+3", "0004"], [1, -2, 3, 4]),  # spaces and signs: the one-pass check takes them
        (["\t5", "6\x0b"], [5, 6]),  # other whitespace: the field-by-field path, the same answer
        (["1_0"], None),  # int() would take it; the protocol does not
        (["٣"], None),  # a digit int() takes, not ASCII
        (["5", ""], None),
        (["+-5"], None),
        ([], []),
    ],
)
def test_integer_fields(fields: list[str], expected: list[int] | None) -> None:
    assert text._ints(fields) == expected


def test_a_decoder_says_what_ends_its_lines_and_how_much_may_come_before_one() -> None:
    replies, commands = text.TextDecoder(), text.TextDecoder(commands=True)
    assert replies.ends == b"\r\n" and commands.ends == b";\r\n"
    assert replies.room() == codes.EVENT_LINE_MAX and commands.room() == codes.LINE_MAX
    assert list(replies.feed(b"TEL,1,2")) == [] and replies.room() == codes.EVENT_LINE_MAX - 7
    assert list(replies.feed(b"x" * replies.room())) == []  # up to the limit: still a line arriving
    assert [type(msg) for msg in replies.feed(b"x")] == [m.Malformed]  # one more: too long, at once
