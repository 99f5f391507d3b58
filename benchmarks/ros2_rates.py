"""odom at 50 and 100 Hz: is the rate held, what it costs per robot, and how many robots one process
bridges before a rate is missed.

Run: ``python -m benchmarks.ros2_rates [--duration S] [--max-robots N] [--backend rclpy|dds]``
(default: both, side by side in one run; rclpy where it can be imported); it runs itself in a
private network namespace (``unshare -n``, ``lo`` up: DDS never reaches a real network) and skips,
saying why, where none can be made.

Each robot is ``omnibot ros2 --ros-backend B --port sim://omni4`` as the command composes it (a runtime at the
odom rate, telemetry at that rate, the cmd_vel source and the publishing sink with its own
namespace ``robotK``), all in this process, stepped by one loop paced to the wall clock. A subscriber
in another process (a cyclonedds participant) counts each robot's ``odom``. Measured over
``--duration`` s after discovery:

* odom published per robot per second, and the share of it a subscriber received (the rate is held
  when every robot publishes >= 95 % of it and >= 95 % arrives); the loop's late ticks (jitter: it
  catches up);
* this process's CPU per robot, % of one core; the same loop without the bridge (the simulators,
  links and runtimes only) is run too, and the difference is the bridge's own cost;
* robots per process at 50 Hz: 1, 2, 4, 6, ... until the rate is missed (at most ``--max-robots``).
  The simulators run in this process too: on a real fleet (serial links) the bridge's share is what
  each robot adds.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import math
import os
import signal
import subprocess
import sys
import time
from dataclasses import dataclass
from typing import Any

from benchmarks.netns import ensure_private

DISCOVERY = 1.5
"""s before counting: the subscriber and the bridges find each other."""
HELD = 0.95
"""Fraction of the rate every robot must get (and of the ticks that must be on time)."""

SUBSCRIBER = r"""
import json, sys, time
from omnibot.ros2.dds import Node, Profile

names = sys.argv[1].split(",")  # prints "ready", then on SIGINT each robot's odom stamps (ns)
node = Node()
deep = Profile(depth=10000)  # nothing overwritten while this process waits for a core
readers = {ns: node.reader(f"/{ns}/odom", "nav_msgs/msg/Odometry", deep) for ns in names}
stamps = {ns: [] for ns in names}
print("ready", flush=True)
try:
    while True:
        for ns, reader in readers.items():
            for sample in reader.take(N=1000):
                if hasattr(sample, "__idl_typename__"):
                    stamps[ns].append(sample.header.stamp.sec * 1_000_000_000 + sample.header.stamp.nanosec)
        time.sleep(0.01)
except KeyboardInterrupt:
    print(json.dumps(stamps), flush=True)
"""


@dataclass
class Result:
    """One run: robots, rate, what was published and delivered, the loop's lateness and the CPU."""

    robots: int
    rate: float
    published: list[float]
    """odom per second per robot the bridges published in the measured window (on the link's clock,
    the TEL samples' rate: the wall clock when the loop keeps up)."""
    delivered: list[float]
    """Fraction of those messages the subscriber received, per robot."""
    late: float
    """Fraction of the loop's ticks that started late (after the next one was due)."""
    cpu: float
    """This process's CPU, % of one core, per robot."""

    @property
    def held(self) -> bool:
        """Every robot published the rate and the subscriber got it (late ticks are jitter: the loop
        catches up, on a machine shared with other work they are the scheduler's)."""
        return (
            min(self.published, default=0.0) >= HELD * self.rate and min(self.delivered, default=0.0) >= HELD
        )


class _Window:
    """The stamps of the odom a bridge publishes while :attr:`open` (a recorder mirror)."""

    def __init__(self) -> None:
        self.open = False
        self.stamps: list[int] = []

    def __call__(self, topic: str, typename: str, data: bytes, ns: int) -> None:
        from omnibot.logs import ODOM

        if self.open and topic == ODOM:
            self.stamps.append(ns)

    def close(self) -> None:
        """Nothing to release."""


def run(robots: int, rate: float, duration: float, *, bridge: bool = True, backend: str = "dds") -> Result:
    """``robots`` bridges on ``backend`` at ``rate`` Hz for ``duration`` s (``bridge`` False: without
    the bridge)."""
    from omnibot.client import robot_session
    from omnibot.protocol import codes
    from omnibot.ros2 import BridgeSettings, RobotSpec, Ros2Sink, attach
    from omnibot.runtime import Runtime

    period = 1.0 / rate
    names = [f"robot{k}" for k in range(robots)]
    windows = [_Window() for _ in names]
    with contextlib.ExitStack() as stack:
        peer = None
        if bridge:  # the subscriber first: its start (python, cyclonedds) is not the bridges' to wait for
            env = dict(os.environ, PYTHONPATH=os.pathsep.join(p for p in sys.path if p))
            command = [sys.executable, "-c", SUBSCRIBER, ",".join(names)]
            peer = subprocess.Popen(command, stdout=subprocess.PIPE, text=True, env=env)
            stack.callback(_end, peer)
            if peer.stdout is None or peer.stdout.readline().strip() != "ready":
                raise RuntimeError("the odom subscriber did not start")
        runtimes = []
        for k, name in enumerate(names):
            session = stack.enter_context(robot_session(f"sim://omni4?seed={k + 1}", "omni4", timeout=0.5))
            runtime = Runtime(session.client, period=period)
            if bridge:
                node = attach(runtime, session.robot, BridgeSettings(backend=backend), RobotSpec.named(name))
                stack.callback(node.close)
                sink = next(s for s in runtime.sinks if isinstance(s, Ros2Sink))
                sink.recorder.mirrors.append(windows[k])
            stack.callback(runtime.close)
            runtime.start()
            session.client.telemetry(period, codes.TEL_MASK)
            runtimes.append(runtime)
        ticks, late, cpu = _loop(runtimes, period, duration, windows)
        delivered = [0.0] * robots
        if peer is not None:
            peer.send_signal(signal.SIGINT)
            out, _ = peer.communicate(timeout=30)
            got = json.loads(out.strip().splitlines()[-1] if out.strip() else "{}")
            delivered = [
                len(set(w.stamps) & set(got.get(n, []))) / max(len(w.stamps), 1)
                for w, n in zip(windows, names, strict=True)
            ]
    published = [len(w.stamps) / duration for w in windows]
    return Result(robots, rate, published, delivered, late / max(ticks, 1), cpu / duration / robots * 100)


def _end(process: subprocess.Popen[Any]) -> None:
    if process.poll() is None:
        process.kill()
    process.wait()


def _loop(
    runtimes: list[Any], period: float, duration: float, windows: list[_Window]
) -> tuple[int, int, float]:
    """Step every runtime each ``period`` of wall time, each robot's link clock kept in step, for
    :data:`DISCOVERY` s and then ``duration`` s with ``windows`` open; the ticks and late ticks of
    that window and its CPU time (s)."""
    clients = [r.client for r in runtimes]
    wall0 = time.monotonic()
    link0 = [c.clock.now() for c in clients]
    ticks = late = k = 0
    cpu0 = math.nan
    while (now := time.monotonic()) - wall0 < DISCOVERY + duration:
        if math.isnan(cpu0) and now - wall0 >= DISCOVERY:
            cpu0, ticks, late = time.process_time(), 0, 0
            for window in windows:
                window.open = True
        for runtime in runtimes:
            runtime.step(now)
        k += 1
        for client, start in zip(clients, link0, strict=True):
            lag = start + k * period - client.clock.now()
            if lag > 0:
                client.sleep(lag)
        rest = wall0 + k * period - time.monotonic()
        ticks += 1
        if rest > 0:
            time.sleep(rest)
        else:
            late += 1
    for window in windows:
        window.open = False
    return ticks, late, time.process_time() - cpu0


def describe(result: Result, baseline: Result | None = None, backend: str = "dds") -> str:
    """One line of the report."""
    text = (
        f"{backend}: {result.robots} robot(s) at {result.rate:.0f} Hz: odom published {min(result.published):.1f}/s, "
        f"{min(result.delivered) * 100:.1f} % delivered per robot (worst), late ticks {result.late * 100:.1f} %, "
        f"CPU {result.cpu:.1f} % of a core per robot"
    )
    if baseline is not None:
        text += f" (without the bridge {baseline.cpu:.1f} %: the bridge {result.cpu - baseline.cpu:.1f} %)"
    return text + ("" if result.held else "  <- rate missed")


def main(argv: list[str] | None = None) -> int:
    """Run the benchmark (in a private network namespace)."""
    argv = sys.argv[1:] if argv is None else argv
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=5.0, help="s measured per run (default 5)")
    parser.add_argument("--max-robots", type=int, default=12, help="robots per process at most (default 12)")
    parser.add_argument("--backend", choices=("rclpy", "dds"), action="append", help="default: both")
    args = parser.parse_args(argv)
    status = ensure_private("benchmarks.ros2_rates", argv)
    if status is not None:
        return status
    from omnibot.ros2 import rclpy_importable

    os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")  # lo is the namespace's one link
    backends = args.backend or (["rclpy", "dds"] if rclpy_importable() else ["dds"])
    for rate in (50.0, 100.0):
        baseline = run(1, rate, args.duration, bridge=False)
        for backend in backends:
            print(describe(run(1, rate, args.duration, backend=backend), baseline, backend), flush=True)
    for backend in backends:
        robots, best = 1, 0
        while robots <= args.max_robots:
            result = run(robots, 50.0, args.duration, backend=backend)
            print(describe(result, backend=backend), flush=True)
            if not result.held:
                break
            best = robots
            robots = 2 if robots == 1 else robots + 2
        print(
            f"{backend}: robots per process at 50 Hz: {best} held"
            + ("" if robots <= args.max_robots else " (the most tried)"),
            flush=True,
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
