"""Time per command of the firmware (parse, check, queue, reply) in CPython and MicroPython.

    python -m benchmarks.firmware_command_time [--robot omni4]

CPython runs the timing in-process; MicroPython (the unix port next to the interpreter, if there)
runs ``firmware_timing.py`` on the files staged as for a board. Each figure is the best of 40 batches
(queued commands: 15 per batch, behind a long motion) minus an empty poll. Seed 000 reports up to
2 ms per command on its Arduino; a board running MicroPython is roughly 20-50x slower than this
machine's unix port.
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

from benchmarks.firmware_timing import measure
from omnibot.firmware.config import build_config, stage_board
from omnibot.robot import load_robot

HERE = Path(__file__).resolve().parent


def micropython_binary() -> str | None:
    near = Path(sys.executable).with_name("micropython")
    return str(near) if near.exists() else shutil.which("micropython")


def run_micropython(config: dict[str, object]) -> dict[str, float] | None:
    mp = micropython_binary()
    if mp is None:
        return None
    with tempfile.TemporaryDirectory() as tmp:
        stage_board(tmp, config)
        proc = subprocess.run(
            [mp, str(HERE / "firmware_timing.py")],
            env={**os.environ, "MICROPYPATH": tmp},
            capture_output=True,
            text=True,
            timeout=300,
            check=True,
        )
    out = {}
    for line in proc.stdout.splitlines():
        label, us = line.rsplit("\t", 1)
        out[label] = float(us)
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--robot", default="omni4")
    args = ap.parse_args(argv)
    config = build_config(load_robot(args.robot))
    cpython = measure(config)
    mp = run_micropython(config)
    print(f"firmware time per command, robot {args.robot} (us)")
    print(f"{'command':34s} {'CPython':>9s} {'MicroPython':>12s}")
    for label, us in cpython:
        mp_us = f"{mp[label]:12.1f}" if mp else f"{'n/a':>12s}"
        print(f"{label:34s} {us:9.1f} {mp_us}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
