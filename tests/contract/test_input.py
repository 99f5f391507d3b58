"""Text input framing: line limits, split and merged commands, byte-by-byte input, garbage."""

from __future__ import annotations

from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from omnibot.client import RobotClient
from omnibot.protocol import linecheck

from .conftest import Backend, RawLink

STATUS_IDLE = b"STATUS,1,0,16,0;POWER,0,0,0,0;MOVE,0,0,0,0\r\n"


def test_64_bytes_accepted_65_rejected(raw: RawLink) -> None:
    raw.write(b"STATUS" + b" " * 58 + b"\n")  # 64 bytes before the terminator
    assert raw.line() == STATUS_IDLE
    raw.write(b"STATUS" + b" " * 59 + b"\n")
    assert raw.line() == b"ERROR,22,command too long\r\n"


def test_overlong_line_dropped_up_to_terminator(raw: RawLink, client: RobotClient) -> None:
    raw.write(b"MOVE,1,40," + b"9" * 300 + b";STATUS\n")
    assert raw.replies(2) == [b"ERROR,22,command too long\r\n", STATUS_IDLE]
    for _ in range(3):  # in pieces: still one command, one ERROR
        raw.write(b"X" * 100)
        client.clock.sleep(0.005)
    raw.write(b"\nSTATUS\n")
    assert raw.replies(2) == [b"ERROR,22,command too long\r\n", STATUS_IDLE]
    raw.nothing_more()


def test_merged_commands_and_terminator_runs(raw: RawLink) -> None:
    raw.write(b"STATUS;HELLO;;\r\n\r\n;STATUS\r;\n")
    assert raw.replies(3) == [STATUS_IDLE, b"HELLO,2,omni4,4\r\n", STATUS_IDLE]
    raw.nothing_more()  # empty commands get no reply


def test_case_spaces_and_plus_signs(raw: RawLink) -> None:
    raw.write(b" move , 1 , +40 , 0 , -0 ;status\n")
    ok, status = raw.replies(2)
    assert ok == b"OK\r\n"
    assert status.startswith(b"STATUS,") and status.endswith(b";MOVE,1,40,0,0\r\n")


def test_command_split_across_writes(client: RobotClient) -> None:
    client.submit_raw(b"MOV", replies=0)
    client.sleep(0.01)
    (ok,) = client.submit_raw(b"E,1,40,0,0;STA", replies=1)
    client.sleep(0.01)
    (status,) = client.submit_raw(b"TUS\n", replies=1)
    assert ok.result().keyword == "OK"
    assert status.result().keyword == "STATUS"


def test_byte_by_byte(raw: RawLink, client: RobotClient) -> None:
    for byte in b"MOVE,1,40,0,0;STATUS\n":
        raw.write(bytes([byte]))
        client.clock.sleep(0.001)
    ok, status = raw.replies(2)
    assert ok == b"OK\r\n"
    assert status.startswith(b"STATUS,") and status.endswith(b";MOVE,1,40,0,0\r\n")


GARBAGE = st.binary(max_size=150) | st.text(st.sampled_from("MOVEDLTAS,;0123456789-+ \r\n"), max_size=80).map(
    str.encode
)


@settings(
    max_examples=15,
    derandomize=True,
    deadline=None,
    database=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture],
)
@given(garbage=GARBAGE)
def test_garbage_then_valid_command_answered(client: RobotClient, backend: Backend, garbage: bytes) -> None:
    lowered = garbage.lower()
    assume(all(word not in lowered for word in (b"mode", b"status", b"hello", b"cal", b"telem")))
    raw = RawLink(client.link)
    raw.write(garbage + b"\nSTOP\nSTATUS\n")
    while True:
        line = raw.line(timeout=3.0)
        if line.startswith(b"STATUS,"):
            break
        assert line == b"OK\r\n" or line.startswith(b"ERROR,"), line
    assert line == STATUS_IDLE


def _checked(body: bytes, tag: bytes | None = None) -> bytes:
    return body + linecheck.suffix(body, tag, True)


def test_checked_text_only_runs_nothing_a_damaged_byte_cut_short(raw: RawLink) -> None:
    """MODE bit 4: a digit turned into ``;`` (or CR, LF) cuts a checked line in two; the piece
    before the cut has no check and the piece after fails its own, so nothing runs. Without the
    bit the first piece is an ordinary unchecked command and would run."""
    raw.write(_checked(b"MODE,16", b"1") + b"\n")
    assert raw.line() == _checked(b"OK", b"1") + b"\r\n"
    cut = _checked(b"MOVE,10,40,0,0", b"7").replace(b"40", b"4;", 1)  # MOVE,10,4 ; 0,0#7*....
    raw.write(cut + b"\n")
    assert raw.replies(2) == [b"ERROR,42,check required\r\n", b"ERROR,26,checksum mismatch\r\n"]
    raw.write(b"STATUS\n")  # typed without a check: refused too
    assert raw.line() == b"ERROR,42,check required\r\n"
    raw.write(_checked(b"STATUS") + b"\n")
    assert raw.line() == _checked(b"STATUS,1,0,16,16;POWER,0,0,0,0;MOVE,0,0,0,0") + b"\r\n"  # nothing ran
    raw.write(_checked(b"MODE,0") + b"\nSTATUS\n")  # a checked MODE ends it
    assert raw.replies(2) == [_checked(b"OK") + b"\r\n", STATUS_IDLE]
    raw.nothing_more()
