"""cmd_vel -> VEL on the controller link: how long a ROS 2 command takes to reach the robot.

Run: ``python -m benchmarks.ros2_latency [--duration S] [--period S]``; it runs itself in a private
network namespace (``unshare -n``, ``lo`` up: DDS never reaches a real network) and skips, saying
why, where none can be made.

The bridge as ``omnibot ros2 --port sim://omni4`` runs it (one runtime paced to the wall clock at
``--period``, the ``cmd_vel`` source and the publishing sink) in this process; a teleop stand-in in
another process (a cyclonedds participant, the wire of rmw_cyclonedds) publishes TwistStamped at
20 Hz (each 0-20 ms after its beat, seeded: the commands fall at every phase of the bridge's cycle,
as an unsynchronised teleop's do), each with a new forward speed, once matched with the bridge. Measured per command: from its publication to the VEL that
carries it being written to the link (a runtime sink placed before the bridge's, which runs right
after the cycle's VEL). A command waits for the next cycle: half a period on average, a period at
most; the rest is DDS delivery and the cycle's own work. A command that a newer one replaced before
a cycle took it (the loop waited longer than 50 ms for a core) never reaches the link: counted.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from argparse import Namespace
from typing import Any

from benchmarks.netns import ensure_private

RATE = 20.0
"""Hz of the teleop stand-in (teleop_twist_joy's)."""
SPEEDS = 20
"""Distinct forward speeds the commands cycle through (0.10 ... 0.29 m/s): each command is told from
its neighbours by its speed."""

PEER = r"""
import json, random, sys, time
from omnibot.logs import schemas
from omnibot.logs.recorder import header, twist
from omnibot.ros2.dds import Node
from omnibot.ros2.types import to_dds

TS = "geometry_msgs/msg/TwistStamped"
duration, rate, speeds = float(sys.argv[1]), float(sys.argv[2]), int(sys.argv[3])
node = Node()
writer = node.writer("cmd_vel", TS)
end = time.monotonic() + 10
while writer.get_publication_matched_status().current_count < 1 and time.monotonic() < end:
    time.sleep(0.01)  # discovery: the bridge's cmd_vel reader matched
time.sleep(0.2)
sent = []
jitter = random.Random(1)
start = time.monotonic()
for k in range(int(duration * rate)):
    vx = 0.10 + 0.01 * (k % speeds)
    message = to_dds(schemas.new(TS, header=header(0, "base_link"), twist=twist(vx, 0.0, 0.0)), TS)
    target = start + k / rate + jitter.uniform(0.0, 0.02)  # every phase of the bridge's cycle
    time.sleep(max(0.0, target - time.monotonic()))
    sent.append((round(vx * 100), time.monotonic()))
    writer.write(message)
print(json.dumps(sent))
"""


def measure(duration: float, period: float) -> dict[str, Any]:
    """Run the bridge and the publisher for ``duration`` s; latencies (s) and counts."""
    from omnibot.client.session import robot_session
    from omnibot.protocol import codes
    from omnibot.ros2.command import attach
    from omnibot.runtime.cycle import Cycle
    from omnibot.runtime.runtime import Runtime
    from omnibot.teleop.pacing import Pacer

    vels: list[tuple[int, float]] = []  # (cm/s decided, time the VEL was on the link)

    def on_link(cycle: Cycle) -> None:
        if cycle.sent is not None and cycle.decision.source == "ros2" and cycle.decision.twist is not None:
            vels.append((round(cycle.decision.twist.vx * 100), time.monotonic()))

    with robot_session("sim://omni4", "omni4", timeout=0.5) as session, tempfile.TemporaryFile("w+") as out:
        client, robot = session.client, session.robot
        runtime = Runtime(client, period=period)
        runtime.add_sink(on_link)  # before the bridge's sink: right after the cycle's VEL
        node = attach(
            runtime, robot, Namespace(namespace="", frame_prefix=None, twist=False, cmd_vel_timeout=0.5)
        )
        env = dict(os.environ)
        env["PYTHONPATH"] = os.pathsep.join([p for p in sys.path if p])
        peer = subprocess.Popen(
            [sys.executable, "-c", PEER, str(duration), str(RATE), str(SPEEDS)], stdout=out, env=env
        )
        try:
            runtime.start()
            client.telemetry(period, codes.TEL_MASK)
            runtime.pacer = Pacer(client, period)
            runtime.run(until=lambda: peer.poll() is not None, duration=duration + 10)
        finally:
            runtime.close()
            node.close()
            if peer.poll() is None:
                peer.kill()
            peer.wait()
        out.seek(0)
        sent = [(int(v), float(t)) for v, t in json.loads(out.read() or "[]")]
    latencies = []
    for k, (value, published) in enumerate(sent):
        following = sent[k + 1][1] if k + 1 < len(sent) else float("inf")
        carried = next((t for v, t in vels if v == value and published <= t < following + 0.5), None)
        if carried is not None:
            latencies.append(carried - published)
    return {"published": len(sent), "carried": len(latencies), "latencies": latencies}


def report(period: float, result: dict[str, Any]) -> None:
    """One line: p50, p99 and max in ms."""
    lat = sorted(result["latencies"])
    if not lat:
        print(f"period {period * 1000:.0f} ms: no command reached the link ({result['published']} published)")
        return
    p99 = lat[min(len(lat) - 1, round(0.99 * (len(lat) - 1)))]
    print(
        f"cycle {period * 1000:.0f} ms: {result['carried']}/{result['published']} commands on the link; "
        f"cmd_vel -> VEL p50 {statistics.median(lat) * 1000:.1f} ms, p99 {p99 * 1000:.1f} ms, "
        f"max {lat[-1] * 1000:.1f} ms"
    )


def main(argv: list[str] | None = None) -> int:
    """Run the benchmark (in a private network namespace)."""
    argv = sys.argv[1:] if argv is None else argv
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=10.0, help="s of commands per period (default 10)")
    parser.add_argument(
        "--period", type=float, action="append", help="runtime cycle, s (repeatable; default 0.02 and 0.01)"
    )
    args = parser.parse_args(argv)
    status = ensure_private("benchmarks.ros2_latency", argv)
    if status is not None:
        return status
    for period in args.period or [0.02, 0.01]:
        report(period, measure(args.duration, period))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
