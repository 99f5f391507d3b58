"""Fuzz targets: any bytes into the controller's text input and into the binary decoders.

Each target raises AssertionError (or whatever escapes the code under test) when an invariant breaks;
``tests/fuzz/test_targets.py`` runs them on a bounded budget in the suite, ``make fuzz`` for a long one
under atheris (coverage-guided, ``python -m tests.fuzz.run``).
"""

from __future__ import annotations

from omnibot.firmware import parser
from omnibot.firmware.config import build_config
from omnibot.firmware.controller import Controller
from omnibot.protocol import binary, codes, linecheck, text
from omnibot.protocol.messages import Malformed
from omnibot.robot import load_robot
from tests.firmware.fakehal import FakeHAL

CONFIG = build_config(load_robot("omni4"))


def _controller() -> tuple[FakeHAL, Controller]:
    hal = FakeHAL(int(CONFIG["motors"]), len(CONFIG["sonar_period_min_ms"]), gyro=0)
    ctrl = Controller(hal, CONFIG)
    hal.tx.clear()
    return hal, ctrl


def firmware_reading(cmd: bytes | None) -> tuple[int, tuple[int, ...]]:
    """(keyword id or -ERROR code or 0 for blank, params) as the controller reads one command."""
    if cmd is None:
        return -codes.E_TOO_LONG, ()
    end, _, _, checked = linecheck.split(cmd)
    if checked == linecheck.BAD_CHECK:
        return -codes.E_CHECKSUM, ()
    params: list[int] = []
    kw = parser.parse(cmd[:end], params)
    if kw > 0:
        low, high = codes.PARAM_COUNTS[kw]
        if not low <= len(params) <= high:
            return -codes.E_PARAM_COUNT, ()
    return kw, tuple(params)


def host_reading(cmd: bytes | None) -> tuple[int, tuple[int, ...]]:
    """The same as :func:`firmware_reading`, by the host codec (protocol/text.py)."""
    if cmd is None:
        return -codes.E_TOO_LONG, ()
    parsed = text.parse_command(cmd)
    if parsed is None:
        return 0, ()
    if isinstance(parsed, Malformed):
        assert parsed.code is not None
        return -parsed.code, ()
    return parsed.TYPE, parsed.params()


def text_input(data: bytes) -> None:
    """Bytes into a controller in text mode: it never raises; while it speaks text every output
    line is ASCII, at most 256 bytes and ends in CR LF; and the firmware and the host codec read
    every command alike (the same command and parameters, or the same ERROR code)."""
    split = parser.LineSplitter(int(CONFIG["line_max"]))
    commands: list[bytes | None] = []
    split.feed(data, commands, [])
    for cmd in commands:
        assert firmware_reading(cmd) == host_reading(cmd), cmd
    hal, ctrl = _controller()
    for i in range(0, len(data), 37):  # in pieces, as a UART delivers them
        hal.rx = data[i : i + 37]
        ctrl.poll()
        hal.t += 1000
        if ctrl.binary:
            return  # a MODE,4 switched it: the rest is binary_input's business
    out = bytes(hal.tx)
    assert not out or out.endswith(b"\r\n"), out[-80:]
    for line in out.split(b"\r\n")[:-1]:
        assert len(line) <= codes.EVENT_LINE_MAX and line.isascii(), line


def binary_input(data: bytes) -> None:
    """Bytes into the host's binary decoder and into a controller in binary mode: neither raises,
    and the controller's output stays frames (0x00-delimited) or its HELLO line."""
    for _ in binary.BinaryDecoder().feed(data):
        pass
    hal, ctrl = _controller()
    hal.rx = b"MODE,4\n"
    ctrl.poll()
    assert ctrl.binary
    hal.tx.clear()
    for i in range(0, len(data), 53):
        hal.rx = data[i : i + 53]
        ctrl.poll()
        hal.t += 1000
        if not ctrl.binary:
            return  # a binary MODE without bit 2: back to text
    out = bytes(hal.tx)
    assert not out or (out.startswith(b"\x00") and out.endswith(b"\x00")), out[:80]
