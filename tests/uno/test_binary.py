"""The UNO firmware's binary protocol against the MicroPython firmware's: the same frames answer
the same frames (version 2: length byte, CRC-32; sequence numbers, seq 0 dropped, duplicates, SYNC,
events, every error a frame can trigger, damaged frames dropped, the probe in text and in binary)."""

from __future__ import annotations

import os
import select
import time

import pytest

from omnibot.client import RobotClient
from omnibot.client.wire import BinaryWire
from omnibot.firmware.config import build_config
from omnibot.firmware.controller import Controller
from omnibot.protocol import codes
from omnibot.protocol.frame import Frame, FrameDecoder, encode_frame, encode_message
from omnibot.protocol.messages import Ok, Vel
from omnibot.robot import load_robot
from tests.firmware.fakehal import FakeHAL

from .conftest import start

MOVE = codes.MOVE


def _damaged(index: int, mask: int) -> bytes:
    frame = bytearray(encode_message(codes.STATUS, 9))
    frame[index] ^= mask
    return bytes(frame)


VERSION = codes.PROTOCOL_VERSION
PROBE = encode_message(codes.HELLO, 1, [VERSION], sync=True) + b";\r\n"


# Each step: bytes the host sends. Frames are compared decoded: (type, seq, SYNC, integers, text).
STEPS: list[bytes] = [
    PROBE,  # text: ERROR lines for the garbage
    b"MODE,4\n",
    encode_message(codes.HELLO, 1, [VERSION], sync=True),
    encode_message(codes.STATUS, 0),  # seq 0 is never a command: dropped
    encode_message(codes.STATUS, 2),
    encode_message(MOVE, 3, [0, 20, 0, 0]),  # ERROR 28
    encode_frame(13, 4),  # ERROR 23: unknown type
    encode_message(MOVE, 5, [1, 40, 0, 0, 0, 0]),  # ERROR 24
    encode_message(MOVE, 6, [40000, 40, 0, 0]),  # ERROR 34
    encode_frame(MOVE, 7, b"\x80"),  # ERROR 25: truncated varint
    encode_message(MOVE, 6, [40000, 40, 0, 0]),  # duplicate: the kept reply again
    encode_message(codes.STATUS, 2),  # duplicate of a STATUS
    encode_message(codes.STATUS, 12),  # out of order: no answer
    _damaged(3, 0x01),  # a bit of the body: the CRC fails, no answer
    _damaged(2, 0x02),  # the length byte: no answer
    _damaged(-2, 0x10),  # the top check byte above 0x8F: no answer
    encode_message(codes.STATUS, 9)[:-4] + b"\x00",  # cut short: no answer
    encode_message(MOVE, 8, [30000, 40, 30, 0]),
    encode_message(codes.STATUS, 9),
    # OK, then the IDLE event (seq 1, SYNC), acknowledged at once (before its 50 ms retry)
    encode_message(codes.STOP, 10, sync=True) + encode_frame(codes.ACK, 1),
    encode_message(codes.TELEM, 11, [0, 0]),
    encode_message(codes.CAL, 12, [18, 0, 0, 0]),  # ERROR 38
    encode_message(codes.HELLO, 13, [1]),  # ERROR 39: version 1 is withdrawn
    encode_message(codes.MODE, 14, [0]),  # back to text after this OK frame
    b"STATUS\n",
    b"MODE,4\n",
    PROBE,  # binary: the HELLO reply, the text terminators dropped as garbage
    # ERROR 34: varints past 32 bits (the zigzag of 2^32 + 50, 5 bytes) and at 32 bits' end (-2^31's
    # zigzag is 0xFFFFFFFF: one more wraps to 0), not read as 50 and 0
    encode_message(codes.VEL, 2, [(1 << 32) + 50, 0, 0, 100]),
    encode_message(codes.VEL, 3, [-(1 << 31), 0, 0, 100]),
    encode_message(codes.VEL, 4, [0, 0, 0, -(1 << 34)]),
    encode_message(codes.MODE, 5, [0]),
]


def decode_all(data: bytes) -> list[tuple[object, ...] | bytes]:
    """Frames as (type, seq, sync, ints, text); text lines as bytes."""
    out: list[tuple[object, ...] | bytes] = []
    text, sep, rest = data.partition(b"\x00")
    for line in text.split(b"\r\n")[:-1]:  # complete lines only
        if line:
            out.append(line)
    if sep:
        frames: list[Frame] = []
        FrameDecoder().feed(sep + rest, frames)
        for fr in frames:
            ints, tail = fr.fields()
            out.append((fr.type_id, fr.seq, fr.sync, tuple(ints), tail))
    return out


def reference(robot: str) -> list[list[tuple[object, ...] | bytes]]:
    config = build_config(load_robot(robot))
    hal = FakeHAL(config["motors"], len(config["sonar_period_min_ms"]))
    ctrl = Controller(hal, config)
    hal.take()
    out = []
    for data in STEPS:
        hal.rx += data
        ctrl.poll()
        out.append(decode_all(hal.take()))
    return out


def windows(items: list[tuple[object, ...] | bytes]) -> tuple[list[tuple[object, ...] | bytes], list[object]]:
    """The items with each HELLO reply's window (its own per controller) set to None, and the windows."""
    out: list[tuple[object, ...] | bytes] = []
    found: list[object] = []
    for item in items:
        if isinstance(item, tuple) and item[0] == codes.HELLO_REPLY:
            ints = item[3]
            assert isinstance(ints, tuple)
            found.append(ints[2])
            out.append((*item[:3], (*ints[:2], None, *ints[3:]), item[4]))
        else:
            out.append(item)
    return out, found


WINDOWS = {"uno": codes.WINDOW_MIN, "mega": codes.WINDOW}
"""The window each board announces: the UNO the protocol's least (its RAM and receive ring), the Mega
the protocol's full window, as the MicroPython firmware (docs/uno.md)."""


@pytest.mark.parametrize("board", list(WINDOWS))
def test_same_frames_as_the_micropython_firmware(board: str) -> None:
    """The same frames, but for the window each announces in its HELLO reply: the MicroPython
    firmware takes codes.WINDOW, the UNO the protocol's least, the Mega codes.WINDOW too."""
    emu, port = start("omni4", board=board)
    announced: list[object] = []
    try:
        for data, expected in zip(STEPS, reference("omni4"), strict=True):
            os.write(port.fd, data)
            got = b""
            deadline = time.monotonic() + 2.0
            while time.monotonic() < deadline and len(decode_all(got)) < len(expected):
                if select.select([port.fd], [], [], 0.05)[0]:
                    got += os.read(port.fd, 4096)
            # nothing more within 30 ms (less than an event's 50 ms retry)
            if select.select([port.fd], [], [], 0.03)[0]:
                got += os.read(port.fd, 4096)
            ours, uno_windows = windows(decode_all(got))
            theirs, mp_windows = windows(expected)
            assert ours == theirs, data
            assert mp_windows == [codes.WINDOW] * len(uno_windows)
            announced += uno_windows
    finally:
        port.close()
        emu.close()
    assert announced == [WINDOWS[board]] * 2  # the session's HELLO and the last probe's


@pytest.mark.parametrize("board", list(WINDOWS))
def test_a_client_keeps_to_the_window_the_uno_announces(board: str) -> None:
    """The UNO announces the protocol's least window (the Mega the full one); RobotClient keeps to it
    and every command of a stream three windows long is answered."""
    window = WINDOWS[board]
    emu, port = start("omni4", board=board)
    port.close()
    try:
        with RobotClient.open(f"serial://{emu.path}") as client:
            hello = client.use_binary()
            assert hello.window == window
            wire = client._wire
            assert isinstance(wire, BinaryWire) and wire.sender.window == window
            flying = []
            calls = []
            for k in range(3 * window):
                calls.append(client.submit(Vel(30 + k % 60, 0, 0, 100)))
                flying.append(len(wire.sender.pending()))
            assert max(flying) == window
            assert all(isinstance(call.result(timeout=2.0), Ok) for call in calls)
            client.use_text()
    finally:
        emu.close()


@pytest.mark.parametrize("board", list(WINDOWS))
def test_a_duplicate_status_gets_its_kept_reply_on_the_mega(board: str) -> None:
    """The Mega keeps replies of up to 32 frame bytes, a STATUS's included, so a duplicate STATUS is
    answered with the state of then (moving, before a STOP), as the MicroPython firmware answers it;
    the UNO keeps 16 bytes (OK, ERROR, HELLO) and runs that STATUS again: the state of now (idle)."""
    emu, port = start("omni4", board=board)
    try:
        assert port.ask("MODE,4") == ["OK"]
        os.write(port.fd, encode_message(codes.HELLO, 1, [VERSION], sync=True))
        os.write(port.fd, encode_message(MOVE, 2, [30000, 40, 0, 0]))
        os.write(port.fd, encode_message(codes.STATUS, 3))  # moving: its reply is over 16 bytes
        os.write(port.fd, encode_message(codes.STOP, 4))
        os.write(port.fd, encode_message(codes.STATUS, 3))  # the host did not hear the first reply
        got = b""
        deadline = time.monotonic() + 3.0
        replies: list[tuple[object, ...]] = []
        while time.monotonic() < deadline and len(replies) < 2:
            if select.select([port.fd], [], [], 0.05)[0]:
                got += os.read(port.fd, 4096)
            replies = [f for f in decode_all(got) if isinstance(f, tuple) and f[0] == codes.STATUS_REPLY]
    finally:
        port.close()
        emu.close()
    states = [f[3][0] for f in replies]  # type: ignore[index]
    again = codes.STATE_MOVING if board == "mega" else codes.STATE_IDLE
    assert states == [codes.STATE_MOVING, again], replies


@pytest.mark.parametrize("board", list(WINDOWS))
def test_a_frame_with_too_many_integers_is_error_24_on_the_mega(board: str) -> None:
    """A command frame longer than the UNO's 48-byte chunk (30 integers) is dropped unanswered there;
    the Mega reads frames of any length and answers it as the MicroPython firmware does: ERROR 24."""
    frames = [encode_message(codes.HELLO, 1, [VERSION], sync=True), encode_message(MOVE, 2, [1000] * 30)]
    config = build_config(load_robot("omni4"))
    hal = FakeHAL(config["motors"], len(config["sonar_period_min_ms"]))
    ctrl = Controller(hal, config)
    hal.rx += b"MODE,4\n"
    ctrl.poll()
    hal.take()
    hal.rx += b"".join(frames)
    ctrl.poll()
    expected, _ = windows(decode_all(hal.take()))
    assert expected[-1] == (codes.ERROR, 2, False, (codes.E_PARAM_COUNT,), b"")
    emu, port = start("omni4", board=board)
    try:
        assert port.ask("MODE,4") == ["OK"]
        os.write(port.fd, b"".join(frames))
        got = b""
        deadline = time.monotonic() + 1.0
        while time.monotonic() < deadline:
            if select.select([port.fd], [], [], 0.05)[0]:
                got += os.read(port.fd, 4096)
    finally:
        port.close()
        emu.close()
    ours, _ = windows(decode_all(got))
    assert ours == (expected if board == "mega" else expected[:-1]), ours
