"""Exhaustive error detection of the binary frames: no corrupted frame is ever accepted.

For every frame of a set covering every message type at several lengths, each of these is tried
on the frame's wire bytes (delimiters included), sent between two good frames:

* every 1-bit error and every 2-bit error (any two bits, 00 bytes created or destroyed included);
* every single byte dropped;
* every truncation (the frame cut after k bytes, the next frame following) and every start in
  the middle of the frame (a receiver that came up late);
* every 3-bit error of the two shortest frames (OK, MOVE), and 50,000 random 4-bit errors.

A received frame counts as accepted when it parses without error; it must be one of the frames
actually sent (an error may still lose the corrupted frame, never deliver a changed one), and the
frame after it must always come through (resynchronisation). The 1-bit errors, drops and cuts run
through the real incremental decoders; the 2-bit errors (some 865,000) split the stream at the
delimiters and parse each chunk, as FrameDecoder does (``test_split_path_matches_frame_decoder``
checks that the two agree).
"""

from __future__ import annotations

import random
from collections.abc import Iterator

import pytest

from omnibot.protocol import binary, codes, frame

Key = tuple[int, int, bool, bytes]

PREV = frame.encode_message(codes.OK, 200)
NEXT = frame.encode_message(codes.IDLE, 201)

_TEL_TYPICAL = [
    3_600_000,
    123,
    4,
    120,
    -80,
    255,
    -255,
    4,
    100_000,
    -99_000,
    5_000,
    -1,
    -1234,
    1_234_567,
    12_000,
    0,
    0,
]
_TEL_WORST = [
    2**32 - 1,
    255,
    8,
    *([-255] * 8),
    8,
    *([-(2**31)] * 8),
    -32768,
    -(2**31),
    65535,
    3,
    16,
    4,
    -1,
    500,
    0,
    1,
]

FRAMES: list[tuple[str, bytes]] = [
    ("MOVE", frame.encode_message(codes.MOVE, 1, [2, 40, 0, 0])),
    ("MOVE extreme", frame.encode_message(codes.MOVE, 255, [-30000, -100, 359, -99])),
    ("ROTATE", frame.encode_message(codes.ROTATE, 2, [180, -200])),
    ("DELTA", frame.encode_message(codes.DELTA, 3, [0, 0, 10, 0, 36])),
    ("POWER", frame.encode_message(codes.POWER, 4, [100, 10, 20, -30, 255])),
    ("STOP", frame.encode_message(codes.STOP, 5, sync=True)),
    ("VEL", frame.encode_message(codes.VEL, 6, [35, -20, 45, 100])),
    ("VEL worst", frame.encode_message(codes.VEL, 128, [-32768, -32768, -32768, 1000])),
    ("MODE", frame.encode_message(codes.MODE, 7, [4])),
    ("SONAR", frame.encode_message(codes.SONAR, 8, [1, 60, 0, 100, 20])),
    ("TELEM", frame.encode_message(codes.TELEM, 9, [10, 123])),
    ("STATUS", frame.encode_message(codes.STATUS, 10)),
    ("HELLO", frame.encode_message(codes.HELLO, 1, [2], sync=True)),
    ("CAL", frame.encode_message(codes.CAL, 11, [21, 1, 150, 900])),
    ("ACK", frame.encode_message(codes.ACK, 7)),
    ("OK", frame.encode_message(codes.OK, 1)),
    ("ERROR", frame.encode_message(codes.ERROR, 3, [23], b"unknown command")),
    ("ERROR no text", frame.encode_message(codes.ERROR, 4, [40])),
    ("HELLO reply", frame.encode_message(codes.HELLO_REPLY, 1, [2, 4, 32], b"omni4")),
    ("STATUS reply", frame.encode_message(codes.STATUS_REPLY, 10, [1, 0, 16, 4, 0, 0, 0, 0, 2, 40, 30, 0])),
    ("RANGE", frame.encode_message(codes.RANGE, 12, [1, 15])),
    ("WARN", frame.encode_message(codes.WARN, 13, [13])),
    ("ERROR event", frame.encode_message(codes.ERROR_EVENT, 14, [36], b"internal fault")),
    ("IDLE", frame.encode_message(codes.IDLE, 15)),
    ("TEL typical", frame.encode_message(codes.TEL, 0, _TEL_TYPICAL)),
    ("TEL worst", frame.encode_message(codes.TEL, 0, _TEL_WORST)),
    ("zeros", frame.encode_frame(codes.TEL, 0, bytes(40))),
    ("long text", frame.encode_message(codes.WARN, 16, [11], b"speed reduced " * 5)),
]


def key(fr: frame.Frame) -> Key:
    return (fr.type_id, fr.seq, fr.sync, fr.payload)


def parse(wire: bytes) -> Key:
    fr = frame.parse_frame(wire[1:-1])
    assert not fr.error, fr.error
    return key(fr)


SENT_PREV, SENT_NEXT = parse(PREV), parse(NEXT)


def accepted_by_decoder(stream: bytes) -> list[Key]:
    """The good frames the firmware's incremental FrameDecoder finds in ``stream`` (fed bytewise
    in two pieces, as a UART delivers it) and that the host's BinaryDecoder agrees on."""
    out: list[frame.Frame] = []
    dec = frame.FrameDecoder()
    half = len(stream) // 2
    dec.feed(stream[:half], out)
    dec.feed(stream[half:], out)
    firmware = [key(fr) for fr in out if not fr.error]
    host = [p for p in binary.BinaryDecoder().feed(stream) if isinstance(p, binary.Packet)]
    assert len(host) <= len(firmware)  # the host also drops frames whose payload does not decode
    return firmware


def accepted_by_split(stream: bytes, known: dict[bytes, Key | None]) -> list[Key]:
    """The same as :func:`accepted_by_decoder`, faster: split at 00 and parse each chunk."""
    found = []
    for chunk in stream.split(b"\x00"):
        if not chunk:
            continue
        if chunk in known:
            k = known[chunk]
        else:
            fr = frame.parse_frame(chunk)
            k = None if fr.error else key(fr)
        if k is not None:
            found.append(k)
    return found


def check(accepted: list[Key], sent: Key, what: str) -> None:
    allowed = {SENT_PREV, sent, SENT_NEXT}
    assert all(k in allowed for k in accepted), f"{what}: accepted {accepted}"
    assert accepted[-1] == SENT_NEXT, f"{what}: the next frame was lost"
    assert accepted[0] == SENT_PREV, f"{what}: the previous frame was lost"


def flip(data: bytes, *bits: int) -> bytes:
    out = bytearray(data)
    for b in bits:
        out[b >> 3] ^= 1 << (b & 7)
    return bytes(out)


def one_bit(wire: bytes) -> Iterator[tuple[str, bytes]]:
    for b in range(8 * len(wire)):
        yield f"bit {b}", flip(wire, b)


def drops_and_cuts(wire: bytes) -> Iterator[tuple[str, bytes]]:
    for i in range(len(wire)):
        yield f"byte {i} dropped", wire[:i] + wire[i + 1 :]
    for k in range(1, len(wire) - 1):
        yield f"cut after {k} bytes", wire[:k]
        yield f"started at byte {k}", wire[k:]


def test_the_frame_set_covers_every_message_type_and_several_lengths() -> None:
    types = {parse(w)[0] for _, w in FRAMES}
    assert set(codes.PARAM_COUNTS) | {codes.ACK, *codes.REPLIES, *codes.EVENTS, codes.TEL} <= types
    sizes = sorted(len(w) for _, w in FRAMES)
    assert sizes[0] == 2 + frame.MIN_SIZE and sizes[-1] > 80


@pytest.mark.parametrize(("name", "wire"), FRAMES, ids=[n for n, _ in FRAMES])
def test_every_1_bit_error_drop_and_cut_is_rejected(name: str, wire: bytes) -> None:
    sent = parse(wire)
    for what, bad in [*one_bit(wire), *drops_and_cuts(wire)]:
        check(accepted_by_decoder(PREV + bad + NEXT), sent, f"{name}, {what}")


@pytest.mark.parametrize(("name", "wire"), FRAMES, ids=[n for n, _ in FRAMES])
def test_every_2_bit_error_is_rejected(name: str, wire: bytes) -> None:
    sent = parse(wire)
    known: dict[bytes, Key | None] = {PREV[1:-1]: SENT_PREV, NEXT[1:-1]: SENT_NEXT, wire[1:-1]: sent}
    allowed = {SENT_PREV, SENT_NEXT, sent}
    bits = 8 * len(wire)
    for a in range(bits):
        row = bytearray(flip(wire, a))
        for b in range(a + 1, bits):
            row[b >> 3] ^= 1 << (b & 7)
            accepted = accepted_by_split(PREV + bytes(row) + NEXT, known)
            if any(k not in allowed for k in accepted) or (accepted[-1] != SENT_NEXT):
                check(accepted, sent, f"{name}, bits {a} and {b}")
            row[b >> 3] ^= 1 << (b & 7)


def test_split_path_matches_frame_decoder() -> None:
    _, wire = FRAMES[1]
    known: dict[bytes, Key | None] = {}
    for what, bad in [*one_bit(wire), *drops_and_cuts(wire)]:
        stream = PREV + bad + NEXT
        assert accepted_by_split(stream, known) == accepted_by_decoder(stream), what


def test_the_known_holes_of_protocol_version_1_are_closed() -> None:
    """Version 1 accepted a frame whose closing delimiter became 01 (the CRC-16 residue of a
    trailing 00), and truncated frames as other frames."""
    for _, wire in FRAMES:
        bad = wire[:-1] + b"\x01"
        assert accepted_by_decoder(PREV + bad + NEXT) == [SENT_PREV, SENT_NEXT]
        for k in range(2, len(wire) - 1):
            assert frame.parse_frame(wire[1:k]).error


@pytest.mark.parametrize("name", ["OK", "MOVE"])
def test_every_3_bit_error_of_short_frames_is_rejected(name: str) -> None:
    """The promise is every 1..3-bit error: all of them on the shortest frames (OK: 88 bits,
    109,736 errors; MOVE: 120 bits, 280,840 errors)."""
    wire = dict(FRAMES)[name]
    sent = parse(wire)
    known: dict[bytes, Key | None] = {PREV[1:-1]: SENT_PREV, NEXT[1:-1]: SENT_NEXT, wire[1:-1]: sent}
    allowed = {SENT_PREV, SENT_NEXT, sent}
    bits = 8 * len(wire)
    for a in range(bits):
        for b in range(a + 1, bits):
            row = bytearray(flip(wire, a, b))
            for c in range(b + 1, bits):
                row[c >> 3] ^= 1 << (c & 7)
                accepted = accepted_by_split(PREV + bytes(row) + NEXT, known)
                if any(k not in allowed for k in accepted) or accepted[-1] != SENT_NEXT:
                    check(accepted, sent, f"{name}, bits {a}, {b} and {c}")
                row[c >> 3] ^= 1 << (c & 7)


def test_random_4_bit_errors_are_rejected() -> None:
    """4-bit errors are too many to try on every frame; 50,000 drawn with a fixed seed."""
    rng = random.Random(12)
    for _ in range(50_000):
        name, wire = FRAMES[rng.randrange(len(FRAMES))]
        bad = flip(wire, *rng.sample(range(8 * len(wire)), 4))
        accepted = accepted_by_split(PREV + bad + NEXT, {})
        check(accepted, parse(wire), f"{name}, {bad.hex()}")
