"""Protocol throughput on a 115200-baud line, text against binary, through the real firmware.

Run: ``python -m benchmarks.link_throughput [--pty] [--load N] [--window W]``. By default the line is the
in-process lockstep link (a UART paced at 115200 baud in both directions, simulated time,
deterministic). With ``--pty`` the same runs go through ``omnibot sim --pty`` in real time: a
separate process, a pseudo-terminal paced to the baud rate, the firmware running in CPython.
``--load N`` runs N busy processes beside it (each a CPU-bound loop that ends on its own after
LOAD_LIMIT_S, and is stopped when the runs end), to see whether a loaded host keeps the line full;
it matters with ``--pty`` (lockstep time does not depend on the host's speed). ``--window W`` keeps
the binary stream to W frames in flight (8 = the protocol's least, the window before version 2
announced one) to compare windows on the same machine.

1. Commands per second sustained: the host streams ``N`` commands as fast as the line and the
   protocol allow (text: no window, replies in order; binary: the ARQ window the controller
   announces in its HELLO reply, docs/protocol.md)
   and we time until the last reply is in. The command is ``VEL,40,0,0,100`` (immediate, so the
   controller's 16-deep motion queue cannot overflow; a stream of ``MOVE,2,40,0,0`` at line rate
   queues 800 moves of 50 ms per second and must end in ERROR 21). The line limit is 11,520 bytes/s
   divided by the command's length on the wire.
2. Closed-loop load: VEL at 100 Hz with telemetry (powers, encoders, gyro, heading, battery, queue)
   at 100 Hz back, for 10 s: bytes per second in each direction against the line's 11,520.

Also reported, to tell where a slow binary run lost its time: the load average before and after,
the longest wait for a reply during the binary stream and, with ``--pty`` on Linux, the CPU time
and the run-queue wait (runnable, not running: /proc/PID/schedstat) per second of that stream, of
the emulator's process and of the host's thread.
"""

from __future__ import annotations

import argparse
import itertools
import json
import os
import subprocess
import sys
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path

from omnibot.protocol import binary, codes, text
from omnibot.protocol.messages import Hello, HelloReply, Mode, Ok, Telem, Telemetry, Vel
from omnibot.sim import SimDevice, spawn_pty_emulator
from omnibot.transport import Link, LockstepLink, open_link

LINE_BYTES_PER_S = 115200 / 10
LOAD_LIMIT_S = 600
_BUSY = f"import time\nend = time.monotonic() + {LOAD_LIMIT_S}\nwhile time.monotonic() < end:\n    pass\n"
VEL = Vel(40, 0, 0, 100)
TEL_MASK = (
    codes.TEL_POWER
    | codes.TEL_ENCODERS
    | codes.TEL_GYRO
    | codes.TEL_HEADING
    | codes.TEL_BATTERY
    | codes.TEL_QUEUE
)


@contextmanager
def open_line(pty: bool, seed: int = 1, started: Callable[[int], object] | None = None) -> Iterator[Link]:
    """A link to a fresh simulated omni4 controller, lockstep or through the pty emulator (whose
    process id ``started`` hears)."""
    if not pty:
        with LockstepLink(SimDevice("omni4", seed=seed)) as link:
            drain(link, 0.05)
            yield link
        return
    with (
        spawn_pty_emulator("omni4", seed=seed, started=started) as path,
        open_link(f"serial://{path}") as link,
    ):
        drain(link, 0.2)
        yield link


@contextmanager
def busy_processes(n: int) -> Iterator[list[int]]:
    """``n`` CPU-bound processes for the duration of the block (their PIDs); each also stops by
    itself after LOAD_LIMIT_S."""
    procs = [subprocess.Popen([sys.executable, "-c", _BUSY]) for _ in range(n)]
    try:
        yield [p.pid for p in procs]
    finally:
        for p in procs:
            p.terminate()
        for p in procs:
            p.wait(timeout=10)


def load_average() -> float | None:
    """The 1-minute load average (None where /proc/loadavg does not exist)."""
    try:
        return float(Path("/proc/loadavg").read_text().split()[0])
    except OSError:
        return None


def scheduled(path: str) -> tuple[float, float] | None:
    """(s on a CPU, s runnable but waiting for one) so far of the task whose schedstat is at
    ``path`` (/proc/PID/schedstat, /proc/self/task/TID/schedstat); None where there is none."""
    try:
        on_cpu, waiting = Path(path).read_text().split()[:2]
    except (OSError, ValueError):
        return None
    return int(on_cpu) / 1e9, int(waiting) / 1e9


def drain(link: Link, seconds: float) -> bytes:
    """Read whatever arrives for ``seconds`` of the link's clock."""
    end = link.clock.now() + seconds
    out = b""
    while (left := end - link.clock.now()) > 0:
        out += link.read(timeout=left)
    return out


def stream_text(link: Link, n: int) -> float:
    """Send n VEL lines back to back; seconds until the n-th OK."""
    line = text.encode(VEL, terminator=b";")
    t0 = link.clock.now()
    link.write(line * n)
    got, buf = 0, b""
    while got < n:
        chunk = link.read(timeout=2.0)
        if not chunk:
            raise RuntimeError(f"text stream stalled after {got} of {n} replies")
        buf += chunk
        got += buf.count(b"OK\r\n")
        buf = buf[buf.rfind(b"\n") + 1 :]
    return link.clock.now() - t0


def switch_to_binary(link: Link) -> None:
    link.write(text.encode(Mode(codes.MODE_BINARY)))
    reply = b""
    while b"OK\r\n" not in reply:
        chunk = link.read(timeout=1.0)
        if not chunk:
            raise RuntimeError("no OK to MODE,4")
        reply += chunk


def start_session(link: Link) -> int:
    """The session-starting HELLO frame (seq 1, SYNC); the window the host may use: the one the
    controller announces in its reply, at most the host's own (codes.WINDOW)."""
    link.write(binary.encode(Hello(codes.VERSIONS), seq=1, sync=True))
    decoder = binary.BinaryDecoder()
    while True:
        chunk = link.read(timeout=1.0)
        if not chunk:
            raise RuntimeError("no HELLO reply frame")
        for item in decoder.feed(chunk):
            if isinstance(item, binary.Packet) and isinstance(item.message, HelloReply):
                return min(item.message.window, codes.WINDOW)


def stream_binary(link: Link, n: int, window: int, replies_at: list[float] | None = None) -> float:
    """Send n VEL frames (seqs after the HELLO's) with at most ``window`` unacknowledged; seconds
    until the n-th OK. ``replies_at`` gets the link clock's time of every read that brought OKs."""
    frames = [binary.encode(VEL, seq=(k + 1) % codes.SEQ_MAX + 1) for k in range(n)]
    decoder = binary.BinaryDecoder()
    sent = acked = 0
    t0 = link.clock.now()
    while acked < n:
        while sent < n and sent - acked < window:
            link.write(frames[sent])
            sent += 1
        chunk = link.read(timeout=2.0)
        if not chunk:
            raise RuntimeError(f"binary stream stalled after {acked} of {n} replies")
        oks = sum(
            1 for p in decoder.feed(chunk) if isinstance(p, binary.Packet) and isinstance(p.message, Ok)
        )
        acked += oks
        if oks and replies_at is not None:
            replies_at.append(link.clock.now())
    return link.clock.now() - t0


def closed_loop_load(link: Link, binary_mode: bool, seconds: float = 10.0) -> tuple[float, float, int]:
    """VEL every 10 ms and TEL every 10 ms back: (host->controller B/s, controller->host B/s, TEL count)."""
    if binary_mode:
        switch_to_binary(link)
        link.write(binary.encode(Telem(10, TEL_MASK), seq=1))
    else:
        link.write(text.encode(Telem(10, TEL_MASK)))
    drain(link, 0.05)
    decoder: binary.BinaryDecoder | text.TextDecoder = (
        binary.BinaryDecoder() if binary_mode else text.TextDecoder()
    )
    sent = received = tels = 0
    t0 = link.clock.now()
    k = 0
    while link.clock.now() - t0 < seconds:
        frame = binary.encode(VEL, seq=(k + 1) % codes.SEQ_MAX + 1) if binary_mode else text.encode(VEL)
        link.write(frame)
        sent += len(frame)
        k += 1
        next_at = t0 + 0.010 * k
        while (left := next_at - link.clock.now()) > 0:
            chunk = link.read(timeout=left)
            received += len(chunk)
            for item in decoder.feed(chunk):
                message = item.message if isinstance(item, binary.Packet) else item
                tels += isinstance(message, Telemetry)
    elapsed = link.clock.now() - t0
    return sent / elapsed, received / elapsed, tels


def per_second(
    before: tuple[float, float] | None, after: tuple[float, float] | None, seconds: float
) -> list[float] | None:
    """[CPU, run-queue wait] per second between two :func:`scheduled` readings."""
    if before is None or after is None:
        return None
    return [(b - a) / seconds for a, b in zip(before, after, strict=True)]


def run(pty: bool, n: int = 2000, window: int = codes.WINDOW) -> dict[str, object]:
    text_len = len(text.encode(VEL, terminator=b";"))
    bin_len = len(binary.encode(VEL, seq=1))
    load_before = load_average()
    with open_line(pty) as link:
        t_text = stream_text(link, n)
    emulator: list[int] = []
    host = f"/proc/self/task/{threading.get_native_id()}/schedstat"
    with open_line(pty, started=emulator.append) as link:
        switch_to_binary(link)
        window = min(start_session(link), window)
        replies_at: list[float] = []
        emu = f"/proc/{emulator[0]}/schedstat" if emulator else os.devnull
        emu0, host0 = scheduled(emu), scheduled(host)
        t_bin = stream_binary(link, n, window, replies_at)
        emu1, host1 = scheduled(emu), scheduled(host)
    with open_line(pty) as link:
        up_t, down_t, tel_t = closed_loop_load(link, binary_mode=False)
    with open_line(pty) as link:
        up_b, down_b, tel_b = closed_loop_load(link, binary_mode=True)
    gaps = [b - a for a, b in itertools.pairwise(replies_at)]
    return {
        "line": "pty emulator, real time" if pty else "lockstep, simulated time",
        "load_average_before_after": [load_before, load_average()],
        "binary_longest_reply_gap_s": max(gaps, default=0.0),
        "binary_emulator_cpu_wait_per_s": per_second(emu0, emu1, t_bin) if pty else None,
        "binary_host_cpu_wait_per_s": per_second(host0, host1, t_bin) if pty else None,
        "binary_window": window,
        "binary_share_of_line": n / t_bin / (LINE_BYTES_PER_S / bin_len),
        "text_share_of_line": n / t_text / (LINE_BYTES_PER_S / text_len),
        "text_command_bytes": text_len,
        "text_commands_per_s": n / t_text,
        "text_line_limit_per_s": LINE_BYTES_PER_S / text_len,
        "binary_command_bytes": bin_len,
        "binary_commands_per_s": n / t_bin,
        "binary_line_limit_per_s": LINE_BYTES_PER_S / bin_len,
        "closed_loop_text_up_Bps": up_t,
        "closed_loop_text_down_Bps": down_t,
        "closed_loop_text_tel_per_s": tel_t / 10,
        "closed_loop_binary_up_Bps": up_b,
        "closed_loop_binary_down_Bps": down_b,
        "closed_loop_binary_tel_per_s": tel_b / 10,
    }


def report(r: dict[str, object]) -> str:
    def pct(x: object, of: object) -> str:
        return f"{100 * float(x) / float(of):5.1f}%"  # type: ignore[arg-type]

    def sched(who: str, cpu_wait: object) -> str:
        if not isinstance(cpu_wait, list):
            return ""
        cpu, wait = cpu_wait
        return f"; {who} {100 * cpu:.1f}% of a CPU, runnable but waiting {100 * wait:.1f}% of the time"

    line = LINE_BYTES_PER_S
    return "\n".join(
        [
            f"line: {r['line']}, 115200 baud 8N1 = {line:,.0f} bytes/s each way, {r['load']} busy processes beside",
            f"VEL stream, text   ({r['text_command_bytes']} B): {r['text_commands_per_s']:7.1f} commands/s of "
            f"{r['text_line_limit_per_s']:7.1f} line limit = {pct(r['text_commands_per_s'], r['text_line_limit_per_s'])}",
            f"VEL stream, binary ({r['binary_command_bytes']} B, window {r['binary_window']}): "
            f"{r['binary_commands_per_s']:7.1f} commands/s of "
            f"{r['binary_line_limit_per_s']:7.1f} line limit = {pct(r['binary_commands_per_s'], r['binary_line_limit_per_s'])}",
            f"closed loop VEL 100 Hz + TEL 100 Hz, text:   up {r['closed_loop_text_up_Bps']:7.0f} B/s "
            f"({pct(r['closed_loop_text_up_Bps'], line)}), down {r['closed_loop_text_down_Bps']:7.0f} B/s "
            f"({pct(r['closed_loop_text_down_Bps'], line)}), {r['closed_loop_text_tel_per_s']:.0f} TEL/s",
            f"closed loop VEL 100 Hz + TEL 100 Hz, binary: up {r['closed_loop_binary_up_Bps']:7.0f} B/s "
            f"({pct(r['closed_loop_binary_up_Bps'], line)}), down {r['closed_loop_binary_down_Bps']:7.0f} B/s "
            f"({pct(r['closed_loop_binary_down_Bps'], line)}), {r['closed_loop_binary_tel_per_s']:.0f} TEL/s",
            f"binary stream: longest wait for a reply {1e3 * float(r['binary_longest_reply_gap_s']):.0f} ms"  # type: ignore[arg-type]
            + sched("emulator", r["binary_emulator_cpu_wait_per_s"])
            + sched("host", r["binary_host_cpu_wait_per_s"]),
            f"load average before, after: {r['load_average_before_after']}",
        ]
    )


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description="protocol throughput on a 115200-baud line")
    parser.add_argument("--pty", action="store_true", help="through the pty emulator in real time")
    parser.add_argument("--load", type=int, default=0, metavar="N", help="N busy processes beside (0..8)")
    parser.add_argument(
        "--window",
        type=int,
        default=codes.WINDOW,
        metavar="W",
        help=f"binary: at most W frames in flight, if the controller takes that many "
        f"({codes.WINDOW_MIN}..{codes.WINDOW}, default {codes.WINDOW}: what a host sends)",
    )
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args(argv)
    if not 0 <= args.load <= 8:
        parser.error(f"--load must be 0..8, got {args.load}")
    if not codes.WINDOW_MIN <= args.window <= codes.WINDOW:
        parser.error(f"--window must be {codes.WINDOW_MIN}..{codes.WINDOW}, got {args.window}")
    with busy_processes(args.load):
        result = run(args.pty, window=args.window)
    result["load"] = args.load
    print(json.dumps(result) if args.json else report(result))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
