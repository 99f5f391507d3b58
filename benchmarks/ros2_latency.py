"""cmd_vel -> VEL on the controller link: how long a ROS 2 command takes to reach the robot, beside a
plain rclpy relay in the same run.

Run: ``python -m benchmarks.ros2_latency [--duration S] [--rate HZ ...] [--period S]``; it runs itself
in a private network namespace (``unshare -n``, ``lo`` up: DDS never reaches a real network) and
skips, saying why, where none can be made.

The bridge as ``omnibot ros2 --port sim://omni4`` runs it (one runtime paced to the wall clock at
``--period``, 20 ms as ``omnibot ros2``'s, the ``cmd_vel`` source and the publishing sink) in this
process. Beside it, in another process, a plain rclpy relay (ROS 2 Jazzy's rclpy on its default rmw,
Fast DDS: a subscription whose callback encodes the VEL and writes it, to ``/dev/null``: the relay's
"link"), the least a ROS node can do between a command and its wire; skipped, with the reason, where
rclpy cannot be imported. A teleop stand-in in a third process (a cyclonedds participant, the wire
of rmw_cyclonedds) publishes TwistStamped at each ``--rate`` (each up to half a period after its beat,
seeded: the commands fall at every phase of the bridge's cycle, as an unsynchronised teleop's do),
once both have matched, each command numbered in its header's ``stamp.sec``. Measured per command:
from its publication to the VEL that carries it being written (the bridge: submitted to the link by
the runtime; the relay: written). The bridge takes each command as it arrives (a DDS listener wakes
the runtime, which arbitrates and sends: :mod:`omnibot.runtime.wakeup`); a command a newer one
replaced before the bridge could send it is counted as such, and one neither carried nor replaced
as lost. Where rclpy runs, an rclpy subscriber beside the publisher times each ``odom`` the bridge
publishes: rmw's received minus source timestamp.

``--robots N`` (repeatable): robots per process instead, as ``omnibot ros2`` runs several (each its
simulator, runtime in a thread of its own, participant and namespace ``robotK``), each sent cmd_vel
at 50 Hz: the worst robot's cycles a second (held at >= 95 % of the cycle rate), the latencies over
all robots, the process's CPU (after a 2 s run of one robot that is not reported: the first run in a
process pays its imports).

``--hosts``: the same again across a network link (:class:`~omnibot.ros2.netns.TwoHosts`: two
namespaces joined by a veth pair, 192.0.2.1 and 192.0.2.2, made inside the private one): the bridge
and the relay on one host, the publisher and the odom subscriber on the other, discovery by
multicast over the link.
"""

from __future__ import annotations

import argparse
import contextlib
import importlib.util
import json
import math
import os
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from typing import Any

from benchmarks.netns import ensure_private

RATES = (50.0, 100.0)
"""Hz of the teleop stand-in by default (Nav2's controller at 20-100 Hz; teleop_twist_joy's 20)."""
MATCH = 30.0
"""s the publisher waits for the bridge and the relay to match its writer."""

PEER = r"""
import json, random, sys, time
from omnibot.logs import schemas
from omnibot.logs.rosmsg import twist
from omnibot.ros2.dds import Node
from omnibot.ros2.types import to_dds

TS = "geometry_msgs/msg/TwistStamped"
duration, rate, readers = float(sys.argv[1]), float(sys.argv[2]), int(sys.argv[3])
node = Node()
names = sys.argv[5].split(",") if len(sys.argv) > 5 else [""]  # the robots' namespaces
writers = [node.writer(f"/{ns}/cmd_vel" if ns else "cmd_vel", TS) for ns in names]
end = time.monotonic() + float(sys.argv[4])
while time.monotonic() < end and any(w.get_publication_matched_status().current_count < readers for w in writers):
    time.sleep(0.01)  # discovery: each bridge's cmd_vel reader (and the relay's) matched
time.sleep(0.5)
sent = []
jitter = random.Random(1)
start = time.monotonic()
for k in range(int(duration * rate)):
    vx = 0.10 + 0.01 * (k % 20)
    stamp = schemas.new("builtin_interfaces/msg/Time", sec=k, nanosec=0)
    header = schemas.new("std_msgs/msg/Header", stamp=stamp, frame_id="base_link")
    message = to_dds(schemas.new(TS, header=header, twist=twist(vx, 0.0, 0.0)), TS)
    target = start + k / rate + jitter.uniform(0.0, 0.5 / rate)  # every phase of the bridge's cycle
    time.sleep(max(0.0, target - time.monotonic()))
    sent.append(time.monotonic())
    for writer in writers:
        writer.write(message)
time.sleep(0.5)
print(json.dumps(sent))
"""

RELAY = r"""
import json, os, signal, sys, time
import rclpy
from geometry_msgs.msg import TwistStamped
from rclpy.node import Node
from omnibot.protocol import text
from omnibot.protocol.messages import Vel

rclpy.init()
node = Node("cmd_vel_relay")
link = os.open(os.devnull, os.O_WRONLY)
written = {}

def relay(msg):
    t = msg.twist
    line = text.encode(Vel(round(t.linear.x * 100), round(t.linear.y * 100), round(t.angular.z * 57.29578), 200))
    os.write(link, line)
    written.setdefault(msg.header.stamp.sec, time.monotonic())

node.create_subscription(TwistStamped, "cmd_vel", relay, 10)
stop = []
signal.signal(signal.SIGTERM, lambda *_: stop.append(1))
print("ready", flush=True)
while not stop:
    rclpy.spin_once(node, timeout_sec=0.1)
print(json.dumps(written), flush=True)
node.destroy_node()
rclpy.shutdown()
"""


ODOM = r"""
import json, signal
import rclpy
from nav_msgs.msg import Odometry
from rclpy.node import Node

rclpy.init()
node = Node("odom_latency")
latency = []
node.create_subscription(
    Odometry, "odom", lambda m, info: latency.append(info["received_timestamp"] - info["source_timestamp"]), 10
)
stop = []
signal.signal(signal.SIGTERM, lambda *_: stop.append(1))
while not stop:
    rclpy.spin_once(node, timeout_sec=0.1)
print(json.dumps(latency), flush=True)
"""


def _env() -> dict[str, str]:
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([p for p in sys.path if p])
    return env


def relay_unavailable() -> str:
    """Why no rclpy relay runs here ("" when it does)."""
    if importlib.util.find_spec("rclpy") is None:
        return "rclpy is not installed (the test-only extra: pip install 'omnibot[ros2-test]')"
    return ""


def measure(
    duration: float, rate: float, period: float, relay: bool = True, remote: list[str] | None = None
) -> dict[str, Any]:
    """Run the bridge, the relay and the odom subscriber (``relay``: rclpy runs) and the publisher at
    ``rate`` Hz for ``duration`` s; ``remote``: the command prefix that runs the publisher and the
    odom subscriber on the other host."""
    from omnibot.client import Pending, robot_session
    from omnibot.protocol import codes
    from omnibot.protocol.messages import Command, Vel
    from omnibot.ros2 import CmdVelSource, attach
    from omnibot.runtime import Runtime
    from omnibot.teleop import Pacer

    carried: dict[int, float] = {}  # command number -> when its VEL was submitted to the link
    vels: list[tuple[float, int]] = []  # every VEL of cmd_vel's: when, which command's

    with robot_session("sim://omni4", "omni4", timeout=0.5) as session, tempfile.TemporaryFile("w+") as out:
        client, robot = session.client, session.robot
        runtime = Runtime(client, period=period)
        node = attach(runtime, robot)
        source = runtime.sources["ros2"]
        assert isinstance(source, CmdVelSource)
        submit = client.submit

        def on_link(command: Command, timeout: float | None = None) -> Pending:
            pending = submit(command, timeout)
            message = source.message
            if isinstance(command, Vel) and runtime.decision.source == "ros2" and message is not None:
                k = int(message.header.stamp.sec)
                now = time.monotonic()
                carried.setdefault(k, now)
                vels.append((now, k))
            return pending

        client.submit = on_link  # type: ignore[method-assign]
        relayed = odom = None
        there = remote or []
        if relay:
            relayed = subprocess.Popen(
                [sys.executable, "-c", RELAY], stdout=subprocess.PIPE, text=True, env=_env()
            )
            assert relayed.stdout is not None
            relayed.stdout.readline()  # ready
            odom = subprocess.Popen(
                [*there, sys.executable, "-c", ODOM], stdout=subprocess.PIPE, text=True, env=_env()
            )
        peer = subprocess.Popen(
            [*there, sys.executable, "-c", PEER, str(duration), str(rate), "2" if relay else "1", str(MATCH)],
            stdout=out,
            env=_env(),
        )
        try:
            runtime.start()
            client.telemetry(period, codes.TEL_MASK)
            runtime.pacer = Pacer(client, period)
            runtime.run(until=lambda: peer.poll() is not None, duration=duration + MATCH + 10)
        finally:
            runtime.close()
            node.close()
            for process in (peer, relayed, odom):
                if process is not None and process.poll() is None:
                    process.terminate()
            peer.wait()
            relay_out = relayed.communicate(timeout=30)[0] if relayed is not None else ""
            odom_out = odom.communicate(timeout=30)[0] if odom is not None else ""
        out.seek(0)
        sent = [float(t) for t in json.loads(out.read() or "[]")]
    written = (
        {int(k): float(t) for k, t in json.loads(relay_out.strip().splitlines()[-1]).items()}
        if relay_out.strip()
        else {}
    )
    return {
        "published": len(sent),
        "bridge": _latencies(sent, carried, vels),
        "relay": _latencies(sent, written, []) if relay else None,
        "reactions": runtime.reactions,
        "cycles": runtime.cycles,
        "event_driven": source.event_driven,
        "odom": [int(v) / 1e9 for v in json.loads(odom_out.strip().splitlines()[-1])]
        if odom_out.strip()
        else [],
    }


def _latencies(sent: list[float], carried: dict[int, float], vels: list[tuple[float, int]]) -> dict[str, Any]:
    """Each command's latency to the VEL that carried it; the rest: replaced (the first VEL after it
    carried a newer command) or lost."""
    latencies, replaced, lost = [], 0, 0
    for k, published in enumerate(sent):
        if k in carried:
            latencies.append(carried[k] - published)
        elif any(t >= published and j > k for t, j in vels):
            replaced += 1
        else:
            lost += 1
    return {"latencies": latencies, "replaced": replaced, "lost": lost}


def per_process(robots: int, duration: float, rate: float, period: float) -> dict[str, Any]:
    """``robots`` bridges in this process as ``omnibot ros2`` runs several (each its simulator,
    runtime, participant and namespace ``robotK``, its runtime in a thread of its own, wall-clock
    paced at ``period``), each sent cmd_vel at ``rate`` Hz: per robot the latencies, the cycles a
    second while commands came, and this process's CPU (% of a core) over that window."""
    import threading

    from omnibot.client import Pending, robot_session
    from omnibot.protocol import codes
    from omnibot.protocol.messages import Command, Vel
    from omnibot.ros2 import CmdVelSource, RobotSpec, attach
    from omnibot.runtime import Cycle, Runtime
    from omnibot.teleop import Pacer

    names = [f"robot{k}" for k in range(robots)]
    carried: list[dict[int, float]] = [{} for _ in names]
    vels: list[list[tuple[float, int]]] = [[] for _ in names]
    ticks: list[list[float]] = [[] for _ in names]
    cpu: list[tuple[float, float]] = []
    stop = threading.Event()
    with contextlib.ExitStack() as stack, tempfile.TemporaryFile("w+") as out:
        runtimes = []
        for k, name in enumerate(names):
            session = stack.enter_context(robot_session(f"sim://omni4?seed={k + 1}", "omni4", timeout=0.5))
            client = session.client
            runtime = Runtime(client, period=period)
            spec = RobotSpec.named(name)
            stack.callback(attach(runtime, session.robot, spec=spec).close)
            stack.callback(runtime.close)
            source = runtime.sources["ros2"]
            assert isinstance(source, CmdVelSource)

            def on_link(
                command: Command,
                timeout: float | None = None,
                k: int = k,
                submit: Callable[[Command, float | None], Pending] = client.submit,
                source: CmdVelSource = source,
            ) -> Pending:
                pending = submit(command, timeout)
                if isinstance(command, Vel) and source.message is not None:
                    now, index = time.monotonic(), int(source.message.header.stamp.sec)
                    carried[k].setdefault(index, now)
                    vels[k].append((now, index))
                return pending

            client.submit = on_link  # type: ignore[method-assign]

            def tick(cycle: Cycle, k: int = k) -> None:
                ticks[k].append(time.monotonic())
                if k == 0:
                    cpu.append((ticks[0][-1], time.process_time()))

            runtime.add_sink(tick)
            runtimes.append(runtime)

        def serve(runtime: Runtime) -> None:
            runtime.start()
            runtime.client.telemetry(period, codes.TEL_MASK)
            runtime.pacer = Pacer(runtime.client, period)
            runtime.run(until=stop.is_set)

        threads = [threading.Thread(target=serve, args=(r,)) for r in runtimes]
        for thread in threads:
            thread.start()
        peer = subprocess.Popen(
            [sys.executable, "-c", PEER, str(duration), str(rate), "1", str(MATCH), ",".join(names)],
            stdout=out,
            env=_env(),
        )
        try:
            peer.wait(timeout=duration + MATCH + 30)
        finally:
            stop.set()
            for thread in threads:
                thread.join()
            if peer.poll() is None:
                peer.kill()
            peer.wait()
        out.seek(0)
        sent = [float(t) for t in json.loads(out.read() or "[]")]
    first, last = (sent[0], sent[-1]) if sent else (0.0, 0.0)
    window = [(t, c) for t, c in cpu if first <= t <= last]
    busy = (window[-1][1] - window[0][1]) / (window[-1][0] - window[0][0]) if len(window) > 1 else math.nan
    return {
        "published": len(sent),
        "robots": [_latencies(sent, carried[k], vels[k]) for k in range(robots)],
        "rates": [sum(first <= t <= last for t in ts) / max(last - first, 1e-9) for ts in ticks],
        "cpu": busy * 100,
    }


def _percentiles(values: list[float]) -> str:
    """p50, p99 and max of ``values`` (s) in ms."""
    lat = sorted(values)
    p99 = lat[min(len(lat) - 1, round(0.99 * (len(lat) - 1)))]
    return f"p50 {statistics.median(lat) * 1000:.2f} ms, p99 {p99 * 1000:.2f} ms, max {lat[-1] * 1000:.2f} ms"


def report(rate: float, period: float, result: dict[str, Any], where: str = "one host") -> None:
    """One line each for the bridge and the relay (commands carried, p50, p99 and max in ms), one for
    odom's delivery."""
    published = result["published"]
    print(
        f"{where}: cmd_vel at {rate:.0f} Hz, cycle {period * 1000:.0f} ms: {published} published; the bridge "
        f"reacted {result['reactions']} times in {result['cycles']} cycles (listener: {result['event_driven']})"
    )
    for who in ("bridge", "relay"):
        r = result[who]
        if r is None:
            print(f"  {who}: not run ({relay_unavailable()})")
            continue
        lat = r["latencies"]
        if not lat:
            print(f"  {who}: no command reached the link")
            continue
        print(
            f"  {who}: {len(lat)}/{published} on the link ({r['replaced']} replaced, {r['lost']} lost); "
            f"cmd_vel -> VEL {_percentiles(lat)}"
        )
    if result["odom"]:
        print(f"  odom to rclpy: {len(result['odom'])} delivered, {_percentiles(result['odom'])}")


def report_robots(robots: int, period: float, result: dict[str, Any]) -> None:
    """One line: the worst robot's cycles a second, p50 and p99 over all robots, losses, CPU."""
    lat = [v for r in result["robots"] for v in r["latencies"]]
    lost = sum(r["lost"] for r in result["robots"])
    replaced = sum(r["replaced"] for r in result["robots"])
    held = min(result["rates"]) >= 0.95 / period
    print(
        f"{robots} robot(s), cmd_vel at 50 Hz each: cycles {min(result['rates']):.1f}/s (worst robot), "
        f"{len(lat)}/{result['published'] * robots} commands on the links ({replaced} replaced, {lost} lost), "
        f"cmd_vel -> VEL {_percentiles(lat) if lat else 'none'}; CPU {result['cpu']:.0f} % of a core"
        + ("" if held else "  <- cycle rate missed")
    )


def main(argv: list[str] | None = None) -> int:
    """Run the benchmark (in a private network namespace)."""
    argv = sys.argv[1:] if argv is None else argv
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--duration", type=float, default=10.0, help="s of commands per rate (default 10)")
    parser.add_argument(
        "--rate", type=float, action="append", help="Hz of cmd_vel (repeatable; default 50 and 100)"
    )
    parser.add_argument("--period", type=float, default=0.02, help="the runtime's cycle, s (default 0.02)")
    parser.add_argument(
        "--hosts", action="store_true", help="again across a veth link between two namespaces"
    )
    parser.add_argument(
        "--robots",
        type=int,
        action="append",
        help="robots per process at 50 Hz cmd_vel instead (repeatable, e.g. 1 2 4 6 8)",
    )
    parser.add_argument("--remote", help=argparse.SUPPRESS)  # --hosts' run on the robot's host
    args = parser.parse_args(argv)
    rates = args.rate or RATES
    relay = not relay_unavailable()
    if args.remote is not None:  # on the robot's host of --hosts: the other is the prefix's
        os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "SUBNET"
        for rate in rates:
            report(
                rate,
                args.period,
                measure(args.duration, rate, args.period, relay, args.remote.split()),
                "two hosts",
            )
        return 0
    status = ensure_private("benchmarks.ros2_latency", argv)
    if status is not None:
        return status
    if args.robots:
        per_process(1, 2.0, 50.0, args.period)  # warm-up, not reported: the first run pays the imports
        for robots in args.robots:
            report_robots(robots, args.period, per_process(robots, args.duration, 50.0, args.period))
        return 0
    for rate in rates:
        report(rate, args.period, measure(args.duration, rate, args.period, relay))
    if args.hosts:
        from omnibot.ros2.netns import TwoHosts

        with TwoHosts() as hosts:
            inner = [sys.executable, "-m", "benchmarks.ros2_latency", "--remote", " ".join(hosts.prefix(1))]
            inner += ["--duration", str(args.duration), "--period", str(args.period)]
            inner += [a for rate in rates for a in ("--rate", str(rate))]
            hosts.run(0, inner, env=_env()).wait()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
