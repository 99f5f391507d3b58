"""The tag and check suffix of text lines (MicroPython-safe, shared by firmware and host)."""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from omnibot.protocol import linecheck as lc


def test_crc16_check_value_and_the_bitwise_loop_agree() -> None:
    assert lc.crc16(b"123456789") == lc.CHECK == lc.crc16_bitwise(b"123456789")


@given(st.binary(max_size=80))
def test_crc16_bitwise_matches(data: bytes) -> None:
    assert lc.crc16(data) == lc.crc16_bitwise(data)


@pytest.mark.parametrize(
    ("line", "body", "tag", "checked"),
    [
        (b"STATUS", b"STATUS", None, lc.NO_CHECK),
        (b"STATUS#7", b"STATUS", b"7", lc.NO_CHECK),
        (b"STATUS#0042", b"STATUS", b"0042", lc.NO_CHECK),
        (b"STATUS#12345", b"STATUS#12345", None, lc.NO_CHECK),  # five digits: no tag
        (b"STATUS#", b"STATUS#", None, lc.NO_CHECK),
        (b"STATUS#7 ", b"STATUS#7 ", None, lc.NO_CHECK),  # nothing may follow a suffix
        (b"STATUS*12G4", b"STATUS*12G4", None, lc.NO_CHECK),  # not a check: stays in the body
        (b"#7", b"", b"7", lc.NO_CHECK),
    ],
)
def test_split(line: bytes, body: bytes, tag: bytes | None, checked: int) -> None:
    end, start, stop, got = lc.split(line)
    assert (line[:end], None if start < 0 else line[start:stop], got) == (body, tag, checked)


@given(body=st.binary(max_size=50), tag=st.none() | st.integers(0, 9999).map(lambda n: str(n).encode()))
def test_suffix_round_trip_and_any_single_bit_flip_is_caught(body: bytes, tag: bytes | None) -> None:
    line = body + lc.suffix(body, tag, True)
    end, start, stop, checked = lc.split(line)
    assert checked == lc.CHECKED
    if tag is not None:
        assert (line[:end], line[start:stop]) == (body, tag)
    for i in range(len(line) - 4):  # every bit the check covers, and the "*"
        for bit in range(8):
            bad = bytearray(line)
            bad[i] ^= 1 << bit
            assert lc.split(bytes(bad))[3] != lc.CHECKED


def test_lowercase_hex_is_accepted() -> None:
    line = b"STOP" + lc.suffix(b"STOP", b"3", True)
    assert lc.split(line.lower().replace(b"stop", b"STOP"))[3] == lc.CHECKED
