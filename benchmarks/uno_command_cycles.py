"""Cycles per command of the Arduino UNO firmware, in simavr at 16 MHz, and text throughput.

    python -m benchmarks.uno_command_cycles [--robot omni4] [--reps 20] [--board uno|mega]

The firmware sleeps at the end of every main-loop pass; the harness (firmware-avr/unosim) counts the
cycles the CPU is awake between two sleeps. A command is answered in the pass that reads its
terminator, so the longest pass after sending it is that command's cost (parse, check, queue or
execute, reply queued for the UART; interrupts that land in the pass included). Figures are the
median of ``--reps`` sends; the worst is in brackets. Seed 000 measured about 2 ms per command on
its Arduino. Throughput at 115200 baud: ``VEL`` with one command outstanding, and back to back (300
and 1000 raw; 600 through RobotClient, with its text window and without).
"""

from __future__ import annotations

import argparse
import contextlib
import os
import select
import statistics
import time

from benchmarks.link_throughput import (
    VEL,
    closed_loop_load,
    drain,
    start_session,
    stream_binary,
    switch_to_binary,
)
from omnibot.protocol import binary, codes, linecheck
from omnibot.transport import open_link
from omnibot.uno import UnoEmulator, missing_tools

F_CPU = 16e6
LINE_BYTES_PER_S = 11520
CRLF = b"\r\n"


def tagged(command: str, tag: str = "12") -> str:
    """``command`` with a tag and its CRC-16 check (docs/protocol.md, Tags and checks)."""
    data = command.encode()
    return (data + linecheck.suffix(data, tag.encode(), True)).decode()


# (label, setup sent first, the measured command, cleanup)
CASES = [
    ("MOVE (queued)", "MOVE,400,30,0,0", "MOVE,10,40,0,0", "STOP"),
    ("DELTA (queued)", "MOVE,400,30,0,0", "DELTA,0,0,10,0,3", "STOP"),
    ("ROTATE (queued)", "MOVE,400,30,0,0", "ROTATE,90,90", "STOP"),
    ("POWER (queued)", "MOVE,400,30,0,0", "POWER,100,50,50,50,50", "STOP"),
    ("MOVE from idle (starts, computes powers)", "", "MOVE,30000,40,30,10", "STOP"),
    ("VEL (computes powers)", "", "VEL,20,-30,45,1000", "STOP"),
    ("STATUS", "", "STATUS", ""),
    ("STATUS, tagged and checked (#12*...)", "", tagged("STATUS"), ""),
    ("MOVE (queued), tagged and checked", "MOVE,400,30,0,0", tagged("MOVE,10,40,0,0"), "STOP"),
    ("HELLO", "", "HELLO", ""),
    ("TEL line, every group (TELEM,1000,255 sends one at once)", "", "TELEM,1000,255", "TELEM,0,0"),
    ("ERROR 23 (unknown command)", "", "FOO", ""),
    ("ERROR 28 (speed out of range)", "", "MOVE,10,20,0,0", ""),
]


class Port:
    def __init__(self, path: str) -> None:
        self.fd = os.open(path, os.O_RDWR | os.O_NOCTTY)
        self.buf = b""

    def send(self, text: str) -> None:
        if text:
            os.write(self.fd, text.encode() + b"\n")

    def drain(self, quiet: float = 0.05) -> bytes:
        got = b""
        while select.select([self.fd], [], [], quiet)[0]:
            got += os.read(self.fd, 4096)
        return got

    def count_lines(self, n: int, timeout: float = 30.0) -> None:
        deadline = time.monotonic() + timeout
        while self.buf.count(CRLF) < n:
            left = deadline - time.monotonic()
            if left <= 0:
                raise TimeoutError(f"{self.buf.count(CRLF)} of {n} replies")
            if select.select([self.fd], [], [], left)[0]:
                self.buf += os.read(self.fd, 65536)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--robot", default="omni4")
    ap.add_argument("--reps", type=int, default=20)
    ap.add_argument(
        "--board", choices=["uno", "mega"], default="uno", help="uno, or mega: the Arduino Mega 2560 build"
    )
    args = ap.parse_args(argv)
    reason = missing_tools()
    if reason:
        print(f"skipped: {reason}")
        return 0
    emu = UnoEmulator(args.robot, board=args.board)
    port = Port(emu.path)
    try:
        port.drain()
        print("| command | cycles | µs at 16 MHz |\n|---|---|---|")
        for label, setup, command, cleanup in CASES:
            cycles = []
            for _ in range(args.reps):
                port.send(setup)
                port.drain()
                emu.stats()
                port.send(command)
                port.drain()
                cycles.append(emu.stats()[0])
                port.send(cleanup)
                port.drain()
            med, worst = statistics.median(cycles), max(cycles)
            print(
                f"| {label} | {med:,.0f} ({worst:,}) | {med / F_CPU * 1e6:,.0f} ({worst / F_CPU * 1e6:,.0f}) |"
            )
        emu.stats()
        n = 300
        line = b"VEL,40,0,0,100\n"
        limit = LINE_BYTES_PER_S / len(line)
        start = time.monotonic()
        for _ in range(n):  # one command outstanding: each waits for the previous OK
            port.buf = b""
            os.write(port.fd, line)
            port.count_lines(1)
        paced = n / (time.monotonic() - start)
        longest, awake, elapsed, _ = emu.stats()
        print(
            f"\nVEL, one outstanding: {paced:,.0f} commands/s (line limit {limit:,.0f}/s, "
            f"{100 * paced / limit:.0f} %); CPU awake {100 * awake / elapsed:.0f} % of the time, "
            f"longest pass {longest / F_CPU * 1e6:,.0f} µs"
        )
        for count in (n, 1000):  # back to back at line rate: the receive ring absorbs what is late
            port.buf = b""
            emu.stats()
            os.write(port.fd, line * count)
            with contextlib.suppress(TimeoutError):
                port.count_lines(count, timeout=3.0 + count / limit)
            got = port.buf.count(b"OK")
            _, awake, _, _ = emu.stats()
            print(
                f"VEL back to back at line rate: {got} of {count} answered ({100 * got / count:.0f} %), "
                f"{count - got} lost; {awake / count:,.0f} cycles awake a command "
                f"(the line brings one in {F_CPU * len(line) / LINE_BYTES_PER_S:,.0f})"
            )
            port.send("STOP")
            port.drain()
    finally:
        os.close(port.fd)
        emu.close()
    print(f"deepest stack: {emu.stack_bytes} bytes")
    client_stream(args.robot, board=args.board)
    throughput(args.robot, board=args.board)
    return 0


def client_stream(robot: str, n: int = 600, board: str = "uno") -> None:
    """``n`` text VELs submitted back to back through RobotClient, half of them turning (longer to
    run than to arrive), with its text window (docs/protocol.md, "Text flow control") and without."""
    from omnibot.client import RobotClient
    from omnibot.errors import OmnibotError
    from omnibot.protocol.messages import Ok, Vel

    for window in (codes.TEXT_WINDOW, None):
        emu = UnoEmulator(robot, board=board)
        try:
            with RobotClient.open(f"serial://{emu.path}", text_window=window) as client:
                start = time.monotonic()
                calls = [
                    client.submit(
                        Vel(40, 0, 0, 100) if k % 2 else Vel(20 + k % 7, -30, 45, 1000), timeout=3.0
                    )
                    for k in range(n)
                ]
                ok = 0
                for call in calls:
                    with contextlib.suppress(OmnibotError):
                        ok += isinstance(call.result(), Ok)
                rate = n / (time.monotonic() - start)
                with contextlib.suppress(OmnibotError):
                    client.stop()
        finally:
            emu.close()
        print(
            f"RobotClient, {n} VELs (half turning) submitted back to back, text window "
            f"{window or 'none'}: {ok} answered OK, {n - ok} lost"
            + (f", {rate:,.0f} commands/s" if ok == n else "")
        )


def throughput(robot: str, n: int = 1000, seconds: float = 5.0, board: str = "uno") -> None:
    """Binary VEL stream (with the window the board announces: the UNO 8, the Mega 32) and the 100 Hz
    closed loop, text and binary, measured as benchmarks.link_throughput measures the MicroPython
    firmware."""
    bin_len = len(binary.encode(VEL, seq=1))
    limit = LINE_BYTES_PER_S / bin_len
    emu = UnoEmulator(robot, board=board)
    try:
        with open_link(f"serial://{emu.path}") as link:
            drain(link, 0.2)
            switch_to_binary(link)
            window = start_session(link)
            emu.stats()
            rate = n / stream_binary(link, n, window)
            _, awake, elapsed, _ = emu.stats()
        print(
            f"VEL stream, binary ({bin_len} B, window {window}): {rate:,.0f} commands/s of {limit:,.0f} line limit "
            f"({100 * rate / limit:.0f} %); CPU awake {100 * awake / elapsed:.0f} % of the time, "
            f"{awake / F_CPU / n * 1e6:,.0f} µs a command"
        )
        for binary_mode in (False, True):
            emu.command("reset")  # text mode, TEL off
            with open_link(f"serial://{emu.path}") as link:
                drain(link, 0.2)
                up, down, tels = closed_loop_load(link, binary_mode=binary_mode, seconds=seconds)
            print(
                f"closed loop VEL 100 Hz + TEL 100 Hz, {'binary' if binary_mode else 'text'}: "
                f"up {up:,.0f} B/s ({100 * up / LINE_BYTES_PER_S:.1f} %), down {down:,.0f} B/s "
                f"({100 * down / LINE_BYTES_PER_S:.1f} %), {tels / seconds:.0f} TEL/s"
            )
    finally:
        emu.close()


if __name__ == "__main__":
    raise SystemExit(main())
