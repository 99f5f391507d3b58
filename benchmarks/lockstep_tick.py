"""The CPU of one lockstep tick as the slow tests pay it (issue 28: the test suite's cost).

    python -m benchmarks.lockstep_tick [--repeat 3] [--parts]

A :class:`~omnibot.client.RobotClient` drives omni4's firmware on the simulator over a
:class:`~omnibot.transport.LockstepLink` as the calibration runs do: the acceptance test's perturbed
robot on carpet (seed 3), tagged text commands, TEL every 20 ms with the calibration tap's groups
and wheel odometry on it, open-loop and closed-loop MOVEs and ROTATEs, and a held VEL. Prints the
CPU per device tick (the simulator's step, the firmware's poll every 2 ms, the link and the client
around them), best of ``--repeat`` runs, and a digest of every TEL sample the client decoded, the
true and the odometry's final pose, which must not change when only the cost does. ``--parts`` gives the shares of the simulator's
step and of the firmware's half of the tick in the run's wall time (two clock reads each: about
0.1 us more per part; wall, not CPU, so only a quiet machine's shares mean much).
"""

from __future__ import annotations

import argparse
import hashlib
import math
import time
from collections.abc import Callable

from omnibot.calibration import ACCEPTANCE, perturbed_robot
from omnibot.calibration.tap import TAP_MASK
from omnibot.client import RobotClient, Telemetry
from omnibot.estimation import WheelOdometry
from omnibot.protocol import codes
from omnibot.robot import load_robot
from omnibot.sim import SimDevice
from omnibot.transport import LockstepLink

SEED = 3


def scenario(client: RobotClient) -> None:
    """What a calibration asks of the robot, in small: MOVEs, ROTATEs, a held VEL, both loops."""
    for mode in (0, codes.MODE_CLOSED_LOOP):
        client.mode(closed_loop=bool(mode))
        for course in (0.0, 30.0, 45.0, 90.0):
            client.move(0.5, 0.6, math.radians(course))
            client.move(0.5, 0.6, math.radians(course - 180.0))
            client.wait_idle(30.0)
        client.rotate(math.pi, math.pi / 2)
        client.rotate(-math.pi, math.pi / 2)
        client.wait_idle(30.0)
        for _ in range(20):
            client.vel(0.3, 0.1, 0.2, 0.5)
            client.sleep(0.1)
        client.stop()
        client.sleep(0.5)


def run(parts: dict[str, float] | None = None) -> tuple[float, int, str]:
    """One run: (CPU s, device ticks, digest of the bytes read and the final pose)."""
    nominal = load_robot("omni4")
    device = SimDevice(nominal, true_robot=perturbed_robot(nominal, ACCEPTANCE), surface="carpet", seed=SEED)
    if parts is not None:
        _time_parts(device, parts)
    link = LockstepLink(device)
    samples: list[Telemetry] = []
    with RobotClient(link, nominal) as client:
        odometry = WheelOdometry(nominal)

        def sample(tel: Telemetry) -> None:
            samples.append(tel)
            if tel.encoders is not None:
                odometry.update(tel.encoders, None)

        client.on_telemetry(sample)
        client.telemetry(0.02, TAP_MASK)
        start, wall = time.process_time(), time.perf_counter_ns()
        scenario(client)
        cpu = time.process_time() - start
        if parts is not None:
            parts["wall"] = time.perf_counter_ns() - wall
    seen = repr((samples, device.sim.pose, odometry.pose)).encode()
    return cpu, link.steps, hashlib.sha256(seen).hexdigest()[:16]


def _time_parts(device: SimDevice, parts: dict[str, float]) -> None:
    """Wrap the device's simulator step and firmware half with CPU clocks summed into ``parts``."""

    def timed(name: str, fn: Callable[..., None]) -> Callable[..., None]:
        clock = time.perf_counter_ns
        parts[name] = 0.0

        def wrapper(*args: int) -> None:
            t = clock()
            fn(*args)
            parts[name] += clock() - t

        return wrapper

    firmware = device.controller
    firmware.poll = timed("firmware", firmware.poll)  # type: ignore[method-assign]
    device.sim.step = timed("simulator", device.sim.step)  # type: ignore[method-assign]


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeat", type=int, default=3, help="runs; the best is printed")
    parser.add_argument("--parts", action="store_true", help="time the simulator and firmware apart")
    args = parser.parse_args(argv)
    best: tuple[float, int, str] | None = None
    for _ in range(args.repeat):
        parts: dict[str, float] | None = {} if args.parts else None
        cpu, ticks, digest = run(parts)
        wall = (parts or {}).pop("wall", 0.0)
        split = "".join(f", {k} {v / wall:.0%}" for k, v in (parts or {}).items())
        print(f"{ticks} ticks, {cpu:.2f} s CPU: {cpu / ticks * 1e6:.2f} us/tick{split}; digest {digest}")
        if best is None or cpu < best[0]:
            best = (cpu, ticks, digest)
    assert best is not None
    print(f"best: {best[0] / best[1] * 1e6:.2f} us/tick over {best[1]} ticks; digest {best[2]}")


if __name__ == "__main__":
    main()
