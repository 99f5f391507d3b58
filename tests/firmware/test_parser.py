"""Line splitting and command parsing."""

from __future__ import annotations

import pytest

from omnibot.firmware import parser
from omnibot.protocol import codes


def split(chunks: list[bytes], line_max: int = 64) -> list[bytes | None]:
    sp = parser.LineSplitter(line_max)
    out: list[bytes | None] = []
    ends: list[int] = []
    for c in chunks:
        sp.feed(c, out, ends)
    assert len(ends) == len(out)
    return out


STREAM = b"MOVE,2,40,0,0;DELTA,0,0,10,0,36;\r\n\r\nSTATUS\rHELLO\n;;;STOP;"
EXPECTED = [b"MOVE,2,40,0,0", b"DELTA,0,0,10,0,36", b"STATUS", b"HELLO", b"STOP"]


def test_whole_halves_and_byte_by_byte_agree() -> None:
    assert split([STREAM]) == EXPECTED
    for cut in range(len(STREAM) + 1):
        assert split([STREAM[:cut], STREAM[cut:]]) == EXPECTED
    assert split([STREAM[i : i + 1] for i in range(len(STREAM))]) == EXPECTED


def test_unterminated_command_waits() -> None:
    sp = parser.LineSplitter(64)
    out: list[bytes | None] = []
    ends: list[int] = []
    sp.feed(b"STA", out, ends)
    sp.feed(b"TUS", out, ends)
    assert out == []
    sp.feed(b"\nHEL", out, ends)
    assert out == [b"STATUS"]
    assert ends == [1]  # offset just after the terminator in the last chunk


def test_end_offsets() -> None:
    sp = parser.LineSplitter(64)
    out: list[bytes | None] = []
    ends: list[int] = []
    data = b"MODE,4\r\n\x00\x05"
    sp.feed(data, out, ends)
    assert out == [b"MODE,4"]
    assert data[ends[0] :] == b"\n\x00\x05"


def test_long_command_reported_once_and_dropped_to_terminator() -> None:
    exact = b"X" * 64
    assert split([exact + b";"]) == [exact]
    long = b"M" * 65
    assert split([long + b";STOP;"]) == [None, b"STOP"]
    # split over many chunks, the tail after the limit still dropped
    chunks = [b"A" * 40, b"B" * 40, b"C" * 40, b";HELLO\n"]
    assert split(chunks) == [None, b"HELLO"]


@pytest.mark.parametrize(
    ("text", "kw", "params"),
    [
        (b"MOVE,2,40,0,0", codes.MOVE, [2, 40, 0, 0]),
        (b"move,-2,+40,0,-0", codes.MOVE, [-2, 40, 0, 0]),
        (b" Rotate , 90 , 45 ", codes.ROTATE, [90, 45]),
        (b"STATUS", codes.STATUS, []),
        (b"POWER,1,-32768,32767,0,0", codes.POWER, [1, -32768, 32767, 0, 0]),
    ],
)
def test_parse_ok(text: bytes, kw: int, params: list[int]) -> None:
    p: list[int] = []
    assert parser.parse(text, p) == kw
    assert p == params


@pytest.mark.parametrize(
    ("text", "code"),
    [
        (b"FLY,1", codes.E_UNKNOWN),
        (b"MOVEX", codes.E_UNKNOWN),
        (b"MOVE,1,2,3,4,5,6", codes.E_PARAM_COUNT),
        (b"MOVE,1,x,3,4", codes.E_NOT_INTEGER),
        (b"MOVE,1,,3,4", codes.E_NOT_INTEGER),
        (b"MOVE,1.5,2,3,4", codes.E_NOT_INTEGER),
        (b"MOVE,-,2,3,4", codes.E_NOT_INTEGER),
        (b"MOVE,32768,2,3,4", codes.E_RANGE16),
        (b"MOVE,-32769,2,3,4", codes.E_RANGE16),
        (b"MOVE,99999999999999999999,2,3,4", codes.E_RANGE16),
    ],
)
def test_parse_errors(text: bytes, code: int) -> None:
    assert parser.parse(text, []) == -code


def test_blank_command_is_ignored() -> None:
    assert parser.parse(b"   ", []) == 0


@pytest.mark.parametrize(
    "text",
    [b"MOVE,\x0b1,40,0,0", b"MOVE,1\x0c,40,0,0", b"MOVE,1,40,0,0\x0b", b"MOVE,1,40,0,\x850"],
)
def test_only_space_and_tab_separate(text: bytes) -> None:
    """VT, FF and other bytes str.strip() would eat are part of the field: not an integer."""
    assert parser.parse(text, []) == -codes.E_NOT_INTEGER


def test_vertical_tab_and_form_feed_are_not_blank() -> None:
    assert parser.parse(b"\x0b", []) == -codes.E_UNKNOWN
    assert parser.parse(b"\x0c", []) == -codes.E_UNKNOWN
    assert parser.parse(b" \t ", []) == 0
    assert parser.parse(b"\x0bSTATUS", []) == -codes.E_UNKNOWN


def test_syntax_is_checked_before_ranges() -> None:
    """An out-of-range value ahead of a non-integer: the syntax error (25) wins over the range (34)."""
    assert parser.parse(b"MOVE,99999,x,0,0", []) == -codes.E_NOT_INTEGER
    assert parser.parse(b"MOVE,0,99999,0,1.5", []) == -codes.E_NOT_INTEGER
    p = [7]
    assert parser.parse(b"MOVE,99999,1,0,0", p) == -codes.E_RANGE16
    assert p == []


@pytest.mark.parametrize(
    ("text", "params"),
    [
        (b"MOVE,INF,60,0,0", [30000, 60, 0, 0]),
        (b"move,-inf,60,0,0", [-30000, 60, 0, 0]),
        (b"MOVE, +Inf ,60,0,0", [30000, 60, 0, 0]),
        (b"ROTATE,-INF,90", [-30000, 90]),
        (b"DELTA,0,0,10,0,INF", [0, 0, 10, 0, 30000]),
        (b"DELTA,0,0,10,0,-INF", [0, 0, 10, 0, -30000]),  # syntax fine; the repeat's range refuses it
    ],
)
def test_inf_token_where_the_protocol_allows_it(text: bytes, params: list[int]) -> None:
    p: list[int] = []
    assert parser.parse(text, p) > 0
    assert p == params


@pytest.mark.parametrize(
    "text",
    [
        b"MOVE,1,INF,0,0",
        b"DELTA,INF,0,0,0,1",
        b"POWER,INF,0,0,0,0",
        b"ROTATE,90,INF",
        b"MOVE,INFINITY,40,0,0",
        b"MOVE,IN F,40,0,0",
    ],
)
def test_inf_token_elsewhere_is_not_an_integer(text: bytes) -> None:
    assert parser.parse(text, []) == -codes.E_NOT_INTEGER
