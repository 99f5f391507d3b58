"""What recording a run (``--log FILE.mcap``) costs, at 100 Hz telemetry + VEL at 100 Hz.

Run: ``python -m benchmarks.log_cost [--duration S] [--quick]``. The host drives ``omnibot sim
--pty`` (a separate process, a pseudo-terminal paced to 115200 baud, real time) through the client:
VEL every 10 ms (a beat is skipped while 4 are unanswered) and telemetry (powers, encoders, gyro, heading, battery, queue, sonar) every 10 ms
back, for ``--duration`` s, once without a recorder and once with one (the recorder the commands use:
link bytes, protocol lines, joint_states, imu, range, odom, /tf, cmd_vel). Measured:

* host CPU per second of run (this process: the client, the estimator, the recorder), without and
  with recording, and the difference;
* log bytes per second (zstd chunks) and messages per second;
* messages lost: TEL samples the client received against TEL lines in the log, VEL commands sent
  against ``cmd_vel`` messages, and messages the recorder could not write (goal: none).

``--long MINUTES`` (10 by default with ``--long``) measures instead what a long run costs in file
size and memory: the recorder is fed what it records of one 10 ms cycle (:func:`feed`: a VEL and
its OK, a TEL sample, their link bytes) for that many simulated minutes, as fast as it takes them
(no link, no simulator: they are not what is measured); each simulated minute it prints the file's
size and the process's resident memory. ``tests/logs/test_bounded.py`` runs the same feed for a
minute under ``tracemalloc``.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import tempfile
import time
from pathlib import Path

from omnibot.client import RobotClient, Telemetry, guarded
from omnibot.errors import LinkTimeout
from omnibot.logs import Recorder
from omnibot.logs.reader import LogFile
from omnibot.logs.topics import CMD_VEL, PROTOCOL
from omnibot.protocol import text
from omnibot.protocol.messages import Ok, Vel
from omnibot.protocol.messages import Telemetry as TelMessage
from omnibot.robot import load_robot
from omnibot.sim import spawn_pty_emulator

PERIOD = 0.01
MAX_OUTSTANDING = 4
VEL = Vel(30, 0, 20, 200)
"""0.3 m/s ahead while turning at 20 degrees/s; a 200 ms watchdog."""


def drive(path: str, duration: float, log: Path | None) -> dict[str, float]:
    """VEL + TEL at 100 Hz for ``duration`` s on the pty at ``path``; CPU and counts."""
    robot = load_robot("omni4")
    client = RobotClient.open(f"serial://{path}", robot, timeout=0.5)
    rec = Recorder(log) if log is not None else None
    tels = 0
    vels = 0

    def count(_: Telemetry) -> None:
        nonlocal tels
        tels += 1

    with guarded(client, robot=robot):
        if rec is not None:
            rec.attach(client, robot)
        client.on_telemetry(count)
        client.telemetry(PERIOD)
        cpu0, wall0 = time.process_time(), time.monotonic()
        next_t = wall0
        while time.monotonic() - wall0 < duration:
            if len(client.outstanding) < MAX_OUTSTANDING:  # a slow line: skip a beat, as teleop does
                client.submit(VEL)
                vels += 1
            next_t += PERIOD
            while (left := next_t - time.monotonic()) > 0:
                client.pump(left)
        with contextlib.suppress(LinkTimeout):
            client.drain(2.0)
        cpu, wall = time.process_time() - cpu0, time.monotonic() - wall0
    if rec is not None:
        rec.close()
    return {
        "cpu": cpu,
        "wall": wall,
        "tels": tels,
        "vels": vels,
        "lost": rec.lost if rec else 0,
        "rate": vels / wall,
    }


RATE = 100
"""Cycles per simulated second of :func:`feed`."""


def feed(rec: Recorder, i: int) -> None:
    """Cycle ``i`` of a run at :data:`RATE` Hz as the client reports it to the recorder: VEL out, OK
    and a TEL sample back (encoders, powers, gyro, heading, queue, sonar), with their link bytes."""
    t = i / RATE
    rec.message(t, "command", VEL)
    rec.link_bytes(t, "TX", text.encode(VEL))
    tel = TelMessage(
        i * 10, (90, 90, -90, -90), (3 * i, 3 * i, -3 * i, -3 * i), None, 10, i, 7200, (0, 0), (55,)
    )
    rec.link_bytes(t, "RX", b"OK\r\n" + text.encode(tel, b"\r\n"))
    rec.message(t, "reply", Ok())
    rec.event(Telemetry.from_message(tel, t))


def resident() -> int:
    """This process's resident memory, bytes (Linux)."""
    pages = int(Path("/proc/self/statm").read_text().split()[1])
    return pages * os.sysconf("SC_PAGE_SIZE")


def long_run(minutes: int) -> int:
    """Feed a recorder ``minutes`` simulated minutes of cycles; print size and memory each minute."""
    print(f"long run: {minutes} simulated minutes of {RATE} Hz cycles fed to the recorder")
    print(f"{'minute':>6s} {'file MB':>8s} {'RSS MB':>7s} {'wall s':>7s}")
    rows: list[tuple[int, int, int]] = []
    with tempfile.TemporaryDirectory() as tmp:
        log = Path(tmp) / "long.mcap"
        rec = Recorder(log)
        rec.start(load_robot("omni4"))
        wall0 = time.monotonic()
        per_minute = 60 * RATE
        for minute in range(1, minutes + 1):
            for i in range((minute - 1) * per_minute, minute * per_minute):
                feed(rec, i)
            rec.flush()
            size, rss = log.stat().st_size, resident()
            rows.append((minute, size, rss))
            print(f"{minute:6d} {size / 1e6:8.2f} {rss / 1e6:7.1f} {time.monotonic() - wall0:7.1f}")
        rec.close()
        lost = rec.lost
    (_, size1, rss1), (_, size_n, rss_n) = rows[0], rows[-1]
    per_min = (size_n - size1) / max(1, minutes - 1)
    print(
        f"file: {size_n / 1e6:.1f} MB for {minutes} min ({per_min / 1e6:.2f} MB a minute after the first, "
        f"{size1 / 1e6:.2f} MB in the first); memory: {rss1 / 1e6:.1f} MB after 1 min, "
        f"{rss_n / 1e6:.1f} MB after {minutes} ({(rss_n - rss1) / 1e6:+.1f} MB); lost {lost}"
    )
    return 0 if lost == 0 else 1


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=20.0, help="seconds per run (default 20)")
    parser.add_argument("--quick", action="store_true", help="3 s runs (a check that it works)")
    parser.add_argument(
        "--long",
        type=int,
        nargs="?",
        const=10,
        metavar="MINUTES",
        help="file size and memory of a long run instead (default 10 simulated minutes)",
    )
    args = parser.parse_args(argv)
    if args.long is not None:
        return long_run(args.long)
    duration = 3.0 if args.quick else args.duration
    with tempfile.TemporaryDirectory() as tmp:
        log = Path(tmp) / "cost.mcap"
        with spawn_pty_emulator("omni4", seed=1) as path:
            bare = drive(path, duration, None)
        with spawn_pty_emulator("omni4", seed=1) as path:
            recorded = drive(path, duration, log)
        size = log.stat().st_size
        messages = 0
        tel_lines = 0
        cmd_vel = 0
        for m in LogFile.open(log).messages():
            messages += 1
            if m.topic == CMD_VEL:
                cmd_vel += 1
            elif m.topic == PROTOCOL and m.decode().keyword == "TEL":
                tel_lines += 1
    cpu_bare = bare["cpu"] / bare["wall"]
    cpu_rec = recorded["cpu"] / recorded["wall"]
    lost_tel = recorded["tels"] - tel_lines
    lost_vel = recorded["vels"] - cmd_vel
    print(f"run: {duration:g} s, VEL and TEL at {1 / PERIOD:.0f} Hz through omnibot sim --pty (115200 baud)")
    print(
        f"TEL received: {bare['tels']:.0f} without recording, {recorded['tels']:.0f} with; "
        f"VEL sent at {bare['rate']:.0f} and {recorded['rate']:.0f} Hz (at most {MAX_OUTSTANDING} unanswered)"
    )
    print(
        f"host CPU: {100 * cpu_bare:.1f} % without recording, {100 * cpu_rec:.1f} % with "
        f"(+{100 * (cpu_rec - cpu_bare):.1f} % of a core)"
    )
    print(
        f"log: {size / recorded['wall'] / 1000:.1f} kB/s, {messages / recorded['wall']:.0f} messages/s "
        f"({size / 1e6:.2f} MB for {recorded['wall']:.1f} s)"
    )
    print(f"lost: {lost_tel:.0f} TEL, {lost_vel:.0f} VEL, {recorded['lost']:.0f} unwritable (goal: none)")
    return 0 if lost_tel == lost_vel == recorded["lost"] == 0 else 1


if __name__ == "__main__":
    raise SystemExit(main())
