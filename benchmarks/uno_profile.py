"""Where the Arduino UNO firmware spends its cycles on a command: the program counter sampled in simavr.

    python -m benchmarks.uno_profile [--robot omni4] [--command VEL,40,0,0,100] [--reps 200] [--top 25]

The harness (firmware-avr/unosim ``--profile``) samples the program counter every 17 cycles while
the CPU is awake; the command is sent ``--reps`` times, one outstanding (each waits for its reply),
and the samples are summed by function (``avr-nm`` of the ELF). Shares are of the cycles awake,
per command: the main loop's idle passes, the interrupts and the reply's sending included.
"""

from __future__ import annotations

import argparse
import bisect
import os
import subprocess
import tempfile
from pathlib import Path

from benchmarks.uno_command_cycles import Port
from omnibot.uno import UnoEmulator, missing_tools

PROFILE_CYCLES = 17  # unosim.c


def symbols(elf: Path) -> list[tuple[int, str]]:
    """Text symbols as (byte address, demangled name), sorted by address."""
    out = subprocess.run(["avr-nm", "-C", "-n", str(elf)], check=True, capture_output=True, text=True).stdout
    syms = []
    for line in out.splitlines():
        fields = line.split(maxsplit=2)
        if len(fields) == 3 and fields[1] in "tTwW" and int(fields[0], 16) < 0x800000:
            syms.append((int(fields[0], 16), fields[2]))
    return syms


def by_function(samples: dict[int, int], syms: list[tuple[int, str]]) -> dict[str, int]:
    """Samples summed per function (the last symbol at or below each address)."""
    starts = [a for a, _ in syms]
    totals: dict[str, int] = {}
    for addr, n in samples.items():
        k = bisect.bisect_right(starts, addr) - 1
        name = syms[k][1] if k >= 0 else "?"
        totals[name] = totals.get(name, 0) + n
    return totals


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--robot", default="omni4")
    ap.add_argument("--command", default="VEL,40,0,0,100")
    ap.add_argument("--reps", type=int, default=200)
    ap.add_argument("--top", type=int, default=25)
    args = ap.parse_args(argv)
    reason = missing_tools()
    if reason:
        print(f"skipped: {reason}")
        return 0
    with tempfile.TemporaryDirectory() as tmp:
        prof = Path(tmp) / "profile.txt"
        emu = UnoEmulator(args.robot, profile=prof)
        port = Port(emu.path)
        try:
            port.drain()
            emu.command("profile")
            emu.stats()
            for _ in range(args.reps):
                port.buf = b""
                os.write(port.fd, args.command.encode() + b"\n")
                port.count_lines(1)
            _, awake, _, _ = emu.stats()
            port.send("STOP")
        finally:
            os.close(port.fd)
            emu.close()
        samples = {int(a): int(n) for a, n in (line.split() for line in prof.read_text().splitlines())}
        elf = emu.elf
    totals = by_function(samples, symbols(elf))
    total = sum(totals.values())
    print(f"{args.command} x {args.reps}: {awake / args.reps:,.0f} cycles awake a command")
    print("| function | share | cycles a command |\n|---|---|---|")
    for name, n in sorted(totals.items(), key=lambda kv: -kv[1])[: args.top]:
        print(f"| `{name}` | {100 * n / total:.1f} % | {n * PROFILE_CYCLES / args.reps:,.0f} |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
