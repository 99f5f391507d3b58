"""Messages: params()/from_params() round trips, counts, TEL groups, unit helpers."""

from __future__ import annotations

import math
import re
from pathlib import Path

import pytest
from hypothesis import given

from omnibot.errors import ProtocolError
from omnibot.protocol import codes, units
from omnibot.protocol import messages as m
from tests.protocol import strategies as s


@given(s.messages)
def test_params_round_trip(msg: m.Message) -> None:
    cls = type(msg)
    assert cls.from_params(msg.params(), msg.label()) == msg


def test_every_message_type_has_a_keyword_and_a_type_id() -> None:
    for cls in m.MESSAGE_TYPES:
        assert codes.KEYWORDS[cls.TYPE]
        assert m.BY_TYPE[cls.TYPE] is cls
    assert m.BY_TYPE[codes.ERROR_EVENT] is m.ErrorReply
    assert set(m.COMMAND_BY_KEYWORD) == set(codes.COMMANDS)
    assert all(codes.COMMANDS[k] == c.TYPE for k, c in m.COMMAND_BY_KEYWORD.items())


@pytest.mark.parametrize(
    ("cls", "params"),
    [
        (m.Move, [1, 2, 3]),
        (m.Move, [1, 2, 3, 4, 5]),
        (m.Stop, [1]),
        (m.Power, [100]),
        (m.Power, [100, 1, 2, 3, 4, 5]),
        (m.Ok, [0]),
        (m.ErrorReply, []),
        (m.HelloReply, [1]),
        (m.StatusReply, [1, 0, 16, 0, 0, 0, 0]),
        (m.Range, [1]),
        (m.Telemetry, [5]),
    ],
)
def test_wrong_counts_raise(cls: type[m.Message], params: list[int]) -> None:
    with pytest.raises(ProtocolError):
        cls.from_params(params)


def test_keyword_and_description() -> None:
    assert m.Move(1, 2, 3, 4).keyword == "MOVE"
    assert m.HelloReply(1, "omni4", 4).keyword == "HELLO"
    assert m.ErrorReply(23).description == "unknown command"
    assert m.ErrorReply(23, "nope").description == "nope"
    assert m.Warn(13).description == codes.TEXTS[13]


def test_tuples_are_normalised() -> None:
    p = m.Power(100, [1, 2])  # type: ignore[arg-type]
    assert p.powers == (1, 2)
    assert hash(p) == hash(m.Power(100, (1, 2)))
    with pytest.raises(ProtocolError):
        m.StatusReply(1, 0, 16, 0, (), (1, 2))  # type: ignore[arg-type]


def test_check_command() -> None:
    assert m.check_command(m.Move(1, 2, 3, 4)) == (1, 2, 3, 4)
    with pytest.raises(ProtocolError, match="16-bit"):
        m.check_command(m.Move(40000, 2, 3, 4))
    with pytest.raises(ProtocolError, match="more than 5"):
        m.check_command(m.Power(1, (1, 2, 3, 4, 5)))
    assert m.is_command(m.Stop()) and not m.is_command(m.Ok()) and not m.is_command(m.Ack())


def test_telemetry_groups_in_bit_order() -> None:
    t = m.Telemetry(1234, powers=(10, -10, 0), gyro_rate=-150, queue=(0, 2))
    assert t.mask == codes.TEL_POWER | codes.TEL_GYRO | codes.TEL_QUEUE
    assert t.params() == (1234, 73, 3, 10, -10, 0, -150, 0, 2)
    full = m.Telemetry(5, (1,), (2,), (3,), 4, 5, 6, (1, 7), (8,))
    assert full.mask == codes.TEL_MASK
    assert full.params() == (5, 255, 1, 1, 1, 2, 1, 3, 4, 5, 6, 1, 7, 1, 8)
    assert m.Telemetry(7).params() == (7, 0)


def test_telemetry_ignores_unknown_higher_groups() -> None:
    params = (5, codes.TEL_GYRO | 256, -7, 99, 98)
    assert m.Telemetry.from_params(params) == m.Telemetry(5, gyro_rate=-7)


@pytest.mark.parametrize(
    "params",
    [
        (5, codes.TEL_GYRO),  # field missing
        (5, codes.TEL_POWER, 3, 1, 2),  # count larger than the fields
        (5, codes.TEL_POWER, -1),  # negative count
        (5, 0, 1),  # left over
        (5, codes.TEL_QUEUE, 1),
    ],
)
def test_bad_telemetry_raises(params: tuple[int, ...]) -> None:
    with pytest.raises(ProtocolError):
        m.Telemetry.from_params(params)


def test_units() -> None:
    assert units.to_cm(0.4) == 40 and units.from_cm(40) == pytest.approx(0.4)
    assert units.to_deg(math.pi / 2) == 90 and units.from_deg(180) == pytest.approx(math.pi)
    # C = 100 is a 10 cm radius, i.e. curvature 10 1/m
    assert units.to_curvature(10.0) == 100 and units.from_curvature(100) == pytest.approx(10.0)
    assert units.to_ms(0.25) == 250 and units.from_ms(250) == pytest.approx(0.25)
    assert units.to_centideg(math.radians(12.34)) == 1234
    assert units.from_centideg(18000) == pytest.approx(math.pi)
    assert units.from_mv(7400) == pytest.approx(7.4)
    assert units.to_milli(0.85) == 850 and units.from_milli(850) == pytest.approx(0.85)
    assert units.to_cal_k(220.0) == 2200 and units.from_cal_k(2200) == pytest.approx(220.0)
    assert units.clamp16(40000) == 32767 and units.clamp16(-40000) == -32768


DOC = Path(__file__).resolve().parents[2] / "docs" / "protocol.md"


def test_docs_code_table_matches_codes() -> None:
    rows = re.findall(r"^\| (\d+) \| (WARN|ERROR) \|", DOC.read_text(), re.MULTILINE)
    assert {int(code) for code, _ in rows} == set(codes.TEXTS)
    # WARN 10-19 as the seed numbered them; the project's later ones (battery) came after 19 was taken
    warns = {v for k, v in vars(codes).items() if k.startswith("W_") and isinstance(v, int)}
    assert all((kind == "WARN") == (int(code) in warns) for code, kind in rows)
    assert all(c < 20 for c in warns if c not in (codes.W_BATTERY_LIMIT, codes.W_BATTERY_STOP))


def test_docs_tel_example_decodes() -> None:
    from omnibot.protocol import text

    line = re.search(r"^TEL,[-\d,]+$", DOC.read_text(), re.MULTILINE)
    assert line is not None
    _, msg = text.decode(line.group(0).encode() + b"\r\n")
    assert msg == m.Telemetry(
        123456, (120, -120, 118, -119), (5012, -4990, 5033, -5007), gyro_rate=-1250, queue=(0, 2)
    )
    assert isinstance(msg, m.Telemetry) and msg.mask == 75
