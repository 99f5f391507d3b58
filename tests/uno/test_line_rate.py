"""The UNO keeps up with its line: text VELs streamed back to back at 115200 baud are all answered
and all executed (issue 30; BENCHMARKS.md, "Arduino UNO firmware: cycles per command")."""

from __future__ import annotations

import itertools
import os
import threading
import time

import pytest

from omnibot.protocol import codes
from omnibot.uno.emulator import UnoEmulator, UnoError

from .conftest import Port, start

F_CPU = 16_000_000
BYTE_CYCLES = F_CPU * 10 // 115200  # one byte on the line, 8N1

# Two pure translations of the same length, alternated so that every execution changes the duties
FAST, SLOW = "VEL,60,0,0,100\n", "VEL,40,0,0,100\n"


def longest_pass(emu: UnoEmulator, port: Port, command: str, reps: int = 5) -> int:
    """The longest main-loop pass that answers ``command`` (cycles), the median of ``reps`` sends: a
    pass that the battery's reading (every 16 ms, its ADC conversion about 1,700 cycles) happens to
    share is that reading's cost, not the command's."""
    passes = []
    for _ in range(reps):
        port.ask("STOP", skip=("IDLE",))
        emu.stats()
        assert port.ask(command.strip(), skip=("IDLE",)) == ["OK"]
        passes.append(emu.stats()[0])
    port.ask("STOP", skip=("IDLE",))
    return sorted(passes)[reps // 2]


def duties_until_quiet(emu: UnoEmulator, quiet: float = 1.0) -> list[list[int]]:
    """Every duty report until none comes for ``quiet`` s."""
    out = []
    while True:
        try:
            out.append(emu.duties(timeout=quiet)[1])
        except UnoError:  # no report within the quiet time
            return out


def test_a_translating_vel_fits_in_its_time_on_the_line() -> None:
    emu, port = start("omni4")
    try:
        cycles = longest_pass(emu, port, SLOW)
        # the pass that parses, computes the powers and queues the OK, the byte interrupts included
        assert cycles < len(SLOW) * BYTE_CYCLES, f"{cycles} cycles against {len(SLOW) * BYTE_CYCLES}"
    finally:
        port.close()
        emu.close()


def test_300_vels_back_to_back_all_answered_and_executed() -> None:
    emu, port = start("omni4", report=True)
    try:
        port.ask("STOP", skip=("IDLE",))
        duties_until_quiet(emu, 0.3)
        n = 300
        stream = "".join(FAST if k % 2 == 0 else SLOW for k in range(n))
        os.write(port.fd, stream.encode())  # at line rate: the harness feeds one byte per 10 bit times
        started = time.monotonic()
        replies = port.lines(n, timeout=15.0)
        assert replies == ["OK"] * n
        changes = duties_until_quiet(emu)  # the watchdog (100 ms) ends the last VEL: powers off
        assert time.monotonic() - started < 15.0
        # every VEL changed the duties (60 and 40 cm/s alternate), then the watchdog stopped them;
        # the harness samples the pins every 50 us, so a sample may fall between two motors' writes
        assert changes[-1] == [0, 0, 0, 0]
        fast, slow = sorted({tuple(c) for c in changes}, key=lambda c: -changes.count(list(c)))[:2]
        driven = [c for c in changes if tuple(c) in (fast, slow)]
        executions = 1 + sum(a != b for a, b in itertools.pairwise(driven))
        assert executions == n, f"{executions} executions of {n}"
        status = port.ask("STATUS", skip=("IDLE",))[0]
        assert status.startswith(f"STATUS,{codes.STATE_IDLE},0,"), status  # the watchdog's stop, queue empty
    finally:
        port.close()
        emu.close()


def test_the_client_text_window_loses_nothing_of_a_long_mixed_stream() -> None:
    """Streamed for longer than the receive ring can absorb, and with VELs that turn (a pass longer
    than their time on the line): RobotClient's text window (docs/protocol.md, "Text flow control")
    holds the host back, so every command is answered, none lost."""
    from omnibot.client import RobotClient
    from omnibot.protocol.messages import Ok, Vel

    emu, port = start("omni4")
    port.close()
    try:
        with RobotClient.open(f"serial://{emu.path}") as client:
            assert client.text_window == codes.TEXT_WINDOW
            calls = []
            most = 0
            for k in range(600):
                vel = Vel(40, 0, 0, 100) if k % 2 else Vel(20 + k % 7, -30, 45, 1000)
                calls.append(client.submit(vel))
                most = max(most, sum(c.size for c in client.outstanding if not c.done))
            replies = [call.result(timeout=5.0) for call in calls]
            assert all(isinstance(r, Ok) for r in replies)
            assert most <= codes.TEXT_WINDOW
            client.stop()
    finally:
        emu.close()


@pytest.mark.parametrize("board", ["uno", "mega"])
def test_a_host_far_ahead_of_the_line_waits_and_nothing_is_lost(board: str) -> None:
    """1000 VELs (15 KB, more than the harness holds) written at once: the pty fills and the writer
    waits, as for a real serial port, and every command is answered (the harness used to read the
    bytes it had no room for and drop them: 546 of 1000 answered)."""
    emu, port = start("omni4", board=board)
    try:
        port.ask("STOP", skip=("IDLE",))
        n = 1000
        writer = threading.Thread(target=os.write, args=(port.fd, (SLOW * n).encode()))
        writer.start()
        try:
            replies = port.lines(n, timeout=30.0, skip=("IDLE",))
        finally:
            writer.join(timeout=30.0)
        assert replies == ["OK"] * n
    finally:
        port.close()
        emu.close()
