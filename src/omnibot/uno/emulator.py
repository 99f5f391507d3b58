"""The emulated Arduino UNO: omnibot's AVR firmware in simavr, its UART on a pty at 115200 baud.

:func:`build` compiles the firmware of a robot (``make -C firmware-avr ROBOT=... [BOARD=mega]``: the
UNO's ATmega328P, or the Arduino Mega 2560's ATmega2560, which simavr emulates too) and the harness
(``make -C firmware-avr/unosim``); :class:`UnoEmulator` starts the harness and gives the pty's path, which
any serial client opens (``serial://PATH``). Both need a source checkout and Debian's AVR toolchain
and simavr (``make avr-tools``); :func:`missing_tools` says what is absent.

::

    python -m omnibot.uno.emulator omni4 --range 100    # prints the pty path, runs until Ctrl-C
    python -m omnibot.uno.emulator omni4 --board mega   # the Mega build
"""

from __future__ import annotations

import argparse
import fcntl
import select
import shutil
import signal
import subprocess
import sys
from pathlib import Path

from omnibot.errors import OmnibotError

ROOT = Path(__file__).resolve().parents[3]
FIRMWARE_DIR = ROOT / "firmware-avr"
HARNESS_DIR = FIRMWARE_DIR / "unosim"
HARNESS = HARNESS_DIR / "unosim"
SIMAVR_HEADER = Path("/usr/include/simavr/sim_avr.h")
STARTUP_TIMEOUT = 10.0


class UnoError(OmnibotError):
    """The UNO firmware or its emulator could not be built or started."""


def missing_tools() -> str | None:
    """Why the emulated UNO cannot be built here, or None when everything is installed."""
    if not (FIRMWARE_DIR / "Makefile").exists() or not (HARNESS_DIR / "unosim.c").exists():
        return f"the UNO firmware sources are not in {ROOT} (a source checkout is needed)"
    absent = [tool for tool in ("make", "avr-g++", "avr-objcopy", "cc") if shutil.which(tool) is None]
    if not SIMAVR_HEADER.exists():
        absent.append("libsimavr-dev")
    if absent:
        return f"missing {', '.join(absent)}: `make avr-tools` installs Debian's AVR toolchain and simavr"
    return None


BUILD_LOCK = FIRMWARE_DIR / "build" / ".lock"
"""Held while ``make`` runs in the firmware tree: two processes building at once (two test workers,
two emulators started together) would write the same objects."""


def _make(*args: str) -> None:
    BUILD_LOCK.parent.mkdir(parents=True, exist_ok=True)
    with BUILD_LOCK.open("a") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)  # released when the file closes
        proc = subprocess.run(
            ["make", "--no-print-directory", "-s", *args], check=False, capture_output=True, text=True
        )
    if proc.returncode != 0:
        tail = (proc.stdout + proc.stderr).strip().splitlines()[-5:]
        raise UnoError(f"make {' '.join(args)} failed: " + " | ".join(tail))


BOARDS = {"uno": "UNO", "mega": "Mega"}
"""The boards the firmware is built for, with their names in messages: the Arduino UNO and the
Arduino Mega 2560 (docs/uno.md)."""


def generated_dir(board: str = "uno") -> Path:
    """The folder of a board's generated headers and wiring (``firmware-avr/generated[/mega]``)."""
    if board not in BOARDS:
        raise UnoError(f"no board {board!r}: the firmware is built for {', '.join(BOARDS)}")
    return FIRMWARE_DIR / "generated" / ("" if board == "uno" else board)


def build(robot: str, board: str = "uno") -> Path:
    """Build the robot's firmware for ``board`` and the harness (incrementally); returns the ELF."""
    reason = missing_tools()
    if reason:
        raise UnoError(reason)
    gen = generated_dir(board)
    if not (gen / f"{robot}.h").exists():
        known = ", ".join(sorted(p.stem for p in gen.glob("*.h")))
        raise UnoError(
            f"no {BOARDS[board]} firmware for robot {robot!r}: it is generated for {known}"
            " (omnibot.firmware.avrgen)"
        )
    _make("-C", str(FIRMWARE_DIR), f"ROBOT={robot}", f"BOARD={board}")
    build_harness()
    return FIRMWARE_DIR / "build" / ("" if board == "uno" else board) / robot / "omnibot.elf"


def build_harness() -> Path:
    """Build the simavr harness (incrementally); returns its executable."""
    reason = missing_tools()
    if reason:
        raise UnoError(reason)
    _make("-C", str(HARNESS_DIR))
    return HARNESS


def heap_start(elf: Path) -> int | None:
    """The data address of the ELF's ``__heap_start``, where the firmware's stack paint begins (the
    harness measures the deepest stack from there up), or None when ``avr-nm`` does not find it."""
    proc = subprocess.run(["avr-nm", str(elf)], check=False, capture_output=True, text=True)
    for line in proc.stdout.splitlines():
        fields = line.split()
        if len(fields) == 3 and fields[2] == "__heap_start":
            return int(fields[0], 16) & 0xFFFF  # AVR data addresses are 0x800000 + SRAM address
    return None


class UnoEmulator:
    """One running emulated UNO. ``range_cm``: the sonar's fixed reading (None: no echo);
    ``encoder_cps``: encoder counts/s at full PWM duty (None: the wheels stand still); ``report``:
    the harness writes ``pwm T_US D1 .. Dn`` on its stdout when a motor's duty changes (read them
    with :meth:`duties`); ``lockstep``: also ``t T_US`` every emulated millisecond, and the emulator
    waits for ``sync T_US`` (hardware in the loop, :mod:`omnibot.uno.hil`); ``elf``: run this image
    of the robot's firmware (one the Arduino toolchain built from its sketch folder,
    :mod:`omnibot.firmware.avrsketch`) instead of building it with ``firmware-avr/Makefile``;
    ``profile``: the harness samples the program counter while the CPU is awake and writes the counts
    to this file when it stops (``command("profile")`` starts them anew; benchmarks/uno_profile.py);
    ``board``: ``uno`` (ATmega328P) or ``mega`` (the Arduino Mega 2560's ATmega2560, its own pins)."""

    def __init__(
        self,
        robot: str,
        *,
        range_cm: int | None = None,
        encoder_cps: float | None = None,
        report: bool = False,
        lockstep: bool = False,
        elf: Path | None = None,
        profile: Path | None = None,
        board: str = "uno",
    ) -> None:
        self.robot = robot
        self.board = board
        wiring = generated_dir(board) / f"{robot}.board"
        if elf is None:
            elf = build(robot, board)
        else:
            build_harness()
        self.elf = elf
        argv = [str(HARNESS), "--board", str(wiring), str(elf)]
        heap = heap_start(elf) if shutil.which("avr-nm") else None
        if heap is not None:
            argv += ["--heap", str(heap)]
        if range_cm is not None:
            argv += ["--range", str(range_cm)]
        if encoder_cps is not None:
            argv += ["--encoders", str(encoder_cps)]
        if report:
            argv.append("--report")
        if lockstep:
            argv.append("--lockstep")
        if profile is not None:
            argv += ["--profile", str(profile)]
        # unbuffered: readline must not read ahead of what select() reports
        self.proc = subprocess.Popen(
            argv, stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE, bufsize=0
        )
        assert self.proc.stdout is not None
        ready, _, _ = select.select([self.proc.stdout], [], [], STARTUP_TIMEOUT)
        line = self.proc.stdout.readline().decode().strip() if ready else ""
        if not line.startswith("/"):
            _, err = self._stop()
            raise UnoError(f"unosim did not print a pty path: {line!r} {err.strip()}")
        self.path = line
        self.stack_bytes: int | None = None

    def command(self, line: str) -> None:
        """Send the harness a stdin command (``range CM``, ``wheels C1 C2 C3 C4``, ``battery MV``)."""
        assert self.proc.stdin is not None
        self.proc.stdin.write(line.encode() + b"\n")
        self.proc.stdin.flush()

    def stats(self, timeout: float = 5.0) -> tuple[int, int, int, int]:
        """CPU cycles since the last call: (longest main-loop pass, awake, elapsed, passes)."""
        self.command("stats")
        assert self.proc.stdout is not None
        ready, _, _ = select.select([self.proc.stdout], [], [], timeout)
        line = self.proc.stdout.readline().decode().split() if ready else []
        if len(line) != 5 or line[0] != "stats":
            raise UnoError(f"unosim did not answer stats: {line}")
        longest, awake, elapsed, passes = (int(v) for v in line[1:])
        return longest, awake, elapsed, passes

    def duties(self, timeout: float = 5.0) -> tuple[int, list[int]]:
        """The next duty report: (emulated time in us, signed duty of each motor as its pins show)."""
        assert self.proc.stdout is not None
        ready, _, _ = select.select([self.proc.stdout], [], [], timeout)
        fields = self.proc.stdout.readline().decode().split() if ready else []
        if len(fields) < 2 or fields[0] != "pwm":
            raise UnoError(f"unosim sent no duty report: {fields}")
        return int(fields[1]), [int(v) for v in fields[2:]]

    def set_range(self, cm: int | None) -> None:
        """Fix the emulated sonar's reading at ``cm`` (None: no echo)."""
        self.command(f"range {-1 if cm is None else cm}")

    def _stop(self) -> tuple[int, str]:
        if self.proc.poll() is None:
            self.proc.terminate()
        try:
            _, err = self.proc.communicate(timeout=5)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            _, err = self.proc.communicate()
        return self.proc.returncode, err.decode(errors="replace")

    def close(self) -> None:
        """Stop the emulator; ``stack_bytes`` is then the deepest stack the firmware used."""
        if self.proc.returncode is not None and self.stack_bytes is not None:
            return
        code, err = self._stop()
        for line in err.splitlines():
            if line.startswith("stack "):
                self.stack_bytes = int(line.split()[1])
        if code not in (0, -15):
            raise UnoError(f"unosim exited with {code}: {err.strip()}")


def main(argv: list[str] | None = None) -> int:
    """Run the emulated UNO and print its pty's path for a host to open; the exit status."""
    ap = argparse.ArgumentParser(prog="python -m omnibot.uno.emulator", description=__doc__.split("\n")[0])
    ap.add_argument("robot", nargs="?", default="omni4", help="omni4 (seed 000) or mecanum4 (seed 003)")
    ap.add_argument(
        "--range", type=int, default=None, help="the sonar's fixed reading, cm (default: no echo)"
    )
    ap.add_argument("--encoders", type=float, default=None, help="encoder counts/s at full duty")
    ap.add_argument(
        "--board", choices=list(BOARDS), default="uno", help="uno (default) or mega (Arduino Mega 2560)"
    )
    args = ap.parse_args(argv)
    try:
        emu = UnoEmulator(args.robot, range_cm=args.range, encoder_cps=args.encoders, board=args.board)
    except UnoError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 1
    signal.signal(signal.SIGTERM, lambda signum, frame: emu.proc.terminate())
    print(emu.path, flush=True)
    try:
        emu.proc.wait()
    except KeyboardInterrupt:
        pass
    finally:
        emu.close()
    if emu.stack_bytes is not None:
        print(f"deepest stack: {emu.stack_bytes} bytes", file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
