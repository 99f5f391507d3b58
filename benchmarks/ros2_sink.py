"""The ROS 2 bridge's publishing, per runtime cycle: the CPU its sink takes, without the scheduler's noise.

Run: ``python -m benchmarks.ros2_sink [--cycles N] [--backend dds|rclpy ...]``; it runs itself in a
private network namespace (``unshare -n``, ``lo`` up: DDS never reaches a real network) and skips,
saying why, where none can be made.

One robot as ``omnibot ros2 --port sim://omni4`` composes it (:func:`omnibot.ros2.attach`),
telemetry every 20 ms, stepped in lockstep with its simulator (no wall-clock pacing: nothing waits
for a core). Measured: the publishing sink's own CPU (``time.thread_time`` around each call of
:class:`~omnibot.ros2.bridge.Ros2Sink`: the recorder building the messages, the frame prefix, the
serialization, the writers), per cycle, with the robot in a namespace (``robot1``: its frames
prefixed, every message built again) and without one (the recorder's bytes go out as they are). The
thread's CPU time, not the wall clock's: the figure holds on a loaded machine, which the robots per
process at 50 Hz (``benchmarks.ros2_latency --robots``) do not.
"""

from __future__ import annotations

import argparse
import sys
import time
from typing import Any

from benchmarks.netns import ensure_private

WARMUP = 2.0
"""s of the robot's time before measuring (the first messages pay their types' and writers' setup)."""


def sink_cost(backend: str, namespace: str, cycles: int) -> float:
    """The sink's CPU per cycle (s) over ``cycles`` cycles of one robot on ``backend``."""
    from omnibot.client import robot_session
    from omnibot.protocol import codes
    from omnibot.ros2 import BridgeSettings, RobotSpec, Ros2Sink, attach
    from omnibot.runtime import Runtime

    spent = [0.0, 0]

    def timed(cycle: Any, sink: Ros2Sink) -> None:
        start = time.thread_time()
        sink(cycle)
        spent[0] += time.thread_time() - start
        spent[1] += 1

    settings, spec = BridgeSettings(backend=backend), RobotSpec.named(namespace)
    with robot_session("sim://omni4?seed=1", "omni4", timeout=0.5) as session:
        runtime = Runtime(session.client, period=0.02)
        node = attach(runtime, session.robot, settings, spec)
        try:
            sinks = runtime.sinks
            (sink,) = [s for s in sinks if isinstance(s, Ros2Sink)]
            sinks[sinks.index(sink)] = lambda cycle: timed(cycle, sink)
            runtime.start()
            session.client.telemetry(0.02, codes.TEL_MASK)
            runtime.run(duration=WARMUP)
            spent[:] = [0.0, 0]
            runtime.run(until=lambda: spent[1] >= cycles)
        finally:
            runtime.close()
            node.close()
    return spent[0] / spent[1]


def main(argv: list[str] | None = None) -> int:
    """Run the benchmark (in a private network namespace)."""
    argv = sys.argv[1:] if argv is None else argv
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--cycles", type=int, default=1000, help="cycles measured per run (default 1000)")
    parser.add_argument(
        "--backend", choices=("dds", "rclpy"), action="append", help="default: dds, and rclpy where it runs"
    )
    args = parser.parse_args(argv)
    status = ensure_private("benchmarks.ros2_sink", argv)
    if status is not None:
        return status
    from omnibot.ros2 import rclpy_importable

    backends = args.backend or (["dds", "rclpy"] if rclpy_importable() else ["dds"])
    for backend in backends:
        for namespace in ("robot1", ""):
            cost = sink_cost(backend, namespace, args.cycles)
            where = f"namespace {namespace} (frames prefixed)" if namespace else "no namespace"
            print(f"{backend}, {where}: the sink {cost * 1e6:.0f} us of CPU per cycle ({args.cycles} cycles)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
