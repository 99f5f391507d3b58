"""Fixtures: the UNO firmware running in simavr (skipped, with the reason, without the AVR tools);
the same firmware built for the Arduino Mega 2560 (``board="mega"``) runs in simavr too."""

from __future__ import annotations

import os
import select
import time
from collections.abc import Iterator

import pytest

from omnibot.protocol import codes
from omnibot.uno.emulator import UnoEmulator, missing_tools


class Port:
    """The emulated UNO's pty: write text, read CR LF lines (wall clock timeouts)."""

    def __init__(self, path: str) -> None:
        self.fd = os.open(path, os.O_RDWR | os.O_NOCTTY)
        self._buf = b""

    def write(self, text: str) -> None:
        os.write(self.fd, text.encode())

    def lines(self, n: int, timeout: float = 3.0, skip: tuple[str, ...] = ()) -> list[str]:
        """The next ``n`` lines, without their CR LF, leaving out those equal to one of ``skip``."""
        deadline = time.monotonic() + timeout
        out: list[str] = []
        while len(out) < n:
            end = self._buf.find(b"\r\n")
            if end >= 0:
                line = self._buf[:end].decode()
                self._buf = self._buf[end + 2 :]
                if line not in skip:
                    out.append(line)
                continue
            left = deadline - time.monotonic()
            assert left > 0, f"{len(out)} of {n} lines within {timeout} s: {out} {self._buf!r}"
            ready, _, _ = select.select([self.fd], [], [], left)
            if ready:
                self._buf += os.read(self.fd, 4096)
        return out

    def ask(self, text: str, n: int = 1, skip: tuple[str, ...] = ()) -> list[str]:
        self.write(text + "\n")
        return self.lines(n, skip=skip)

    def close(self) -> None:
        os.close(self.fd)


BUILDS = [("omni4", "uno"), ("mecanum4", "uno"), ("omni4", "mega"), ("mecanum4", "mega")]
"""Every (robot, board) the firmware is built for."""
BUILD_IDS = [robot if board == "uno" else f"{robot}-{board}" for robot, board in BUILDS]


def start(
    robot: str,
    range_cm: int | None = None,
    report: bool = False,
    board: str = "uno",
    encoder_cps: float | None = None,
) -> tuple[UnoEmulator, Port]:
    reason = missing_tools()
    if reason:
        pytest.skip(f"emulated UNO: {reason}")
    emu = UnoEmulator(robot, range_cm=range_cm, report=report, board=board, encoder_cps=encoder_cps)
    port = Port(emu.path)
    assert port.lines(1) == [f"HELLO,{codes.PROTOCOL_VERSION},{robot},4"]
    return emu, port


@pytest.fixture(params=BUILDS, ids=BUILD_IDS)
def uno(request: pytest.FixtureRequest) -> Iterator[tuple[UnoEmulator, Port]]:
    robot, board = request.param
    emu, port = start(robot, range_cm=100, board=board)
    try:
        yield emu, port
    finally:
        port.close()
        emu.close()
