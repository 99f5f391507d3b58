"""The fuzz targets on a bounded budget (hypothesis, derandomized) and on known hard inputs."""

from __future__ import annotations

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from omnibot.protocol import binary, frame, linecheck
from omnibot.protocol.messages import Move, Status

from .targets import binary_input, text_input

TEXTY = st.text(
    st.sampled_from("MOVEDLTAPWRSHCIFNK,;#*+- \t\x0b\x0c\r\n0123456789abcdefINF"), max_size=120
).map(lambda s: s.encode("latin-1"))


@settings(
    max_examples=300, derandomize=True, deadline=None, database=None, suppress_health_check=list(HealthCheck)
)
@given(data=st.one_of(TEXTY, st.binary(max_size=200)))
def test_text_input(data: bytes) -> None:
    text_input(data)


@settings(
    max_examples=200, derandomize=True, deadline=None, database=None, suppress_health_check=list(HealthCheck)
)
@given(data=st.binary(max_size=200))
def test_binary_input(data: bytes) -> None:
    binary_input(data)


@pytest.mark.parametrize(
    "data",
    [
        b"MOVE,INF,60,0,0\n\x0b\nMOVE,99999,x,0,0\nSTATUS#12*0000\n",
        b"STOP" + linecheck.suffix(b"STOP", b"7", True) + b"\n" + b"x" * 90 + b"\nMODE,4\n\x00\x01",
        b"HELLO#1*;*ABCD;#;*;" + b"9" * 70,
    ],
)
def test_text_input_known(data: bytes) -> None:
    text_input(data)


def test_binary_input_known() -> None:
    good = binary.encode(Move(2, 40, 0, 0), 1) + binary.encode(Status(), 2)
    binary_input(good)
    binary_input(good[:-3] + b"\x00\x00" + good)
    binary_input(b"\x00" + frame.cobs_encode(b"\x05\x01") + b"\x00HELLO,1,x,4\r\n")
