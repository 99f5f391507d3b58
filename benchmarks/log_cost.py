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
"""

from __future__ import annotations

import argparse
import contextlib
import tempfile
import time
from pathlib import Path

from omnibot.client.client import RobotClient
from omnibot.client.events import Telemetry
from omnibot.client.session import guarded
from omnibot.errors import LinkTimeout
from omnibot.logs.reader import LogFile
from omnibot.logs.recorder import Recorder
from omnibot.logs.topics import CMD_VEL, PROTOCOL
from omnibot.protocol.messages import Vel
from omnibot.robot.description import load_robot
from omnibot.sim.emulator import spawn_pty_emulator

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


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=20.0, help="seconds per run (default 20)")
    parser.add_argument("--quick", action="store_true", help="3 s runs (a check that it works)")
    args = parser.parse_args(argv)
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
