"""Simulator speed: one robot with full wheel dynamics and sensors against IR-SIM, and a batch of 1000.

Run: ``python -m benchmarks.sim_speed`` (``make bench`` runs every benchmark). Both simulators are
measured in the same run on the same machine, so the ratio is meaningful even when the absolute
numbers are not. Results go in BENCHMARKS.md.

* omnibot single: :class:`~omnibot.sim.simulator.Simulator` of the ``omni4`` preset in the ``room``
  world at 1 kHz: motor electrics, wheel dynamics, roller and floor friction, surface patches,
  collisions, encoders, gyro and a sonar pinged every 60 ms. The robot drives into the cabinet
  after about 3 s and keeps pushing against it, so most steps run the full contact test.
* IR-SIM: one kinematic omni robot, headless, no obstacles (:mod:`benchmarks.irsim_baseline`).
* omnibot batch: :class:`~omnibot.sim.physics.Physics` with N = 1000 robots: :meth:`Physics.run`
  (the batch API, every core: robot-steps/s with 1 thread and with all; exact, and with
  ``exact=False``, the robots in vector lanes: :mod:`omnibot.sim.kernels.lanes`) and, for comparison,
  :meth:`Physics.step` called once per step (one core).
* fleet: a :class:`~omnibot.sim.fleet.Fleet` of k = 1, 2, 4, 8 omni4 robots in the room, each with
  its firmware driving a MOVE and pinging its sonar every 60 ms; CPU time (of the stepping thread)
  per fleet step, best of 5; measured before the batch, whose threads may stay busy after it. Source trees
  side by side, in rounds: :mod:`benchmarks.fleet_speed`.
* kernel start-up (skip with ``--no-startup``): seconds from a fresh interpreter's first import of
  the simulator to the end of its first step, with an empty numba cache (the step runs on the
  kernels' twins while a process of its own compiles them: :mod:`omnibot.sim.jit`; the interpreter
  waits for that compile before it ends, outside the figure) and with the cache (kernels loaded
  from disk); numba's import is included.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import sys
import tempfile
import time

import numpy as np

from benchmarks.irsim_baseline import irsim_steps_per_second
from omnibot.robot import load_robot
from omnibot.sim import Physics, Simulator


def omnibot_single_steps_per_second(steps: int = 20000, repeats: int = 3) -> float:
    sim = Simulator(load_robot("omni4"), world="room", seed=1, start_pose=(1.0, 1.0, 0.0))
    sim.set_pwm([40, 150, -40, -150])
    sim.step()  # load (or compile) the kernels outside the timing
    best = 0.0
    for _ in range(repeats):
        t0 = time.perf_counter()
        for k in range(steps):
            sim.step()
            if k % 60 == 0:
                sim.sonar_ping(0)
            if k % 10 == 0:
                sim.encoder_counts()
                sim.gyro_rate()
        best = max(best, steps / (time.perf_counter() - t0))
    return best


def omnibot_batch_robot_steps_per_second(
    n: int = 1000,
    steps: int = 500,
    repeats: int = 3,
    threads: int | None = None,
    exact: bool = True,
    cpu: bool = False,
) -> float:
    """Robot-steps/s of a batch of ``n`` omni4: :meth:`Physics.run` on ``threads`` threads (all
    cores when None; ``exact`` False: its vector lanes), or :meth:`Physics.step` once per step with
    ``threads`` 0; per second of the wall clock, or with ``cpu`` of the process's CPU time (with
    one thread: what one core does, however busy the machine)."""
    import numba

    robot = load_robot("omni4")
    physics = Physics(robot, n=n)
    rng = np.random.default_rng(0)
    pwm = rng.integers(-255, 256, size=(n, robot.n_wheels))
    physics.step(pwm)
    physics.run(pwm, 1, exact=exact)  # compile (or load) both kernels outside the timing
    cores = numba.get_num_threads()
    numba.set_num_threads(threads or cores)
    clock = time.process_time if cpu else time.perf_counter
    best = 0.0
    try:
        for _ in range(repeats):
            t0 = clock()
            if threads == 0:
                for _ in range(steps):
                    physics.step(pwm)
            else:
                physics.run(pwm, steps, exact=exact)
            best = max(best, n * steps / (clock() - t0))
    finally:
        numba.set_num_threads(cores)
    return best


def fleet_step_seconds(k: int, steps: int = 1500, repeats: int = 5) -> float:
    """CPU s per step of a fleet of ``k`` omni4 in the room (firmware, MOVE, sonar every 60 ms)."""
    from omnibot.motion import Pose2D
    from omnibot.sim import Fleet, load_world

    fleet = Fleet(load_world("room"))
    for i in range(k):
        pose = Pose2D(0.6 + 1.2 * (i % 4), 0.5 if i < 4 else 3.5, 0.0)
        device = fleet.add(f"r{i}", "omni4", seed=i, pose=pose)
        device.command("SONAR,1,60,1,500,0;")  # RANGE every 60 ms while something is within 5 m
        device.command("MOVE,100,40,0,0;")
    for _ in range(100):
        fleet.step()
    best = math.inf
    for _ in range(repeats):
        t0 = time.thread_time()  # this thread's CPU: not the batch's numba threads, should they spin
        for _ in range(steps // repeats):
            fleet.step()
        best = min(best, (time.thread_time() - t0) / (steps // repeats))
    return best


_STARTUP = """
import time
t0 = time.perf_counter()
from omnibot.robot.description import load_robot
from omnibot.sim import jit
from omnibot.sim.simulator import Simulator
Simulator(load_robot("omni4"), world="room").step()
print(time.perf_counter() - t0)
jit.active.wait()
"""


def kernel_startup_seconds(cold: bool) -> float:
    """Import + first simulator step in a new interpreter; ``cold`` uses an empty numba cache."""
    env = dict(os.environ)
    with tempfile.TemporaryDirectory() as tmp:
        if cold:
            env["NUMBA_CACHE_DIR"] = tmp
        out = subprocess.run(
            [sys.executable, "-c", _STARTUP], env=env, capture_output=True, text=True, check=True
        )
    return float(out.stdout.split()[-1])


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", action="store_true", help="print the results as JSON")
    parser.add_argument("--no-startup", action="store_true", help="skip the kernel start-up timing")
    args = parser.parse_args(argv)
    ours = omnibot_single_steps_per_second()
    theirs = irsim_steps_per_second()
    fleet = {k: fleet_step_seconds(k) for k in (1, 2, 4, 8)}
    batch_step = omnibot_batch_robot_steps_per_second(threads=0)
    batch_one = omnibot_batch_robot_steps_per_second(threads=1)
    batch = omnibot_batch_robot_steps_per_second()
    lanes_one = omnibot_batch_robot_steps_per_second(threads=1, exact=False)
    exact_cpu = omnibot_batch_robot_steps_per_second(threads=1, cpu=True)
    lanes_cpu = omnibot_batch_robot_steps_per_second(threads=1, exact=False, cpu=True)
    lanes = omnibot_batch_robot_steps_per_second(exact=False)
    result: dict[str, float | None] = {
        "omnibot_single_steps_per_s": round(ours),
        "irsim_steps_per_s": round(theirs) if theirs else None,
        "ratio": round(ours / theirs, 2) if theirs else None,
        "omnibot_batch_1000_step_robot_steps_per_s": round(batch_step),
        "omnibot_batch_1000_run_1_thread_robot_steps_per_s": round(batch_one),
        "omnibot_batch_1000_robot_steps_per_s": round(batch),
        "omnibot_batch_1000_lanes_1_thread_robot_steps_per_s": round(lanes_one),
        "omnibot_batch_1000_lanes_robot_steps_per_s": round(lanes),
        "omnibot_batch_1000_run_robot_steps_per_cpu_s": round(exact_cpu),
        "omnibot_batch_1000_lanes_robot_steps_per_cpu_s": round(lanes_cpu),
        **{f"fleet_{k}_step_us": round(t * 1e6, 1) for k, t in fleet.items()},
        "fleet_8_over_1": round(fleet[8] / fleet[1], 2),
    }
    if not args.no_startup:
        result["startup_cold_s"] = round(kernel_startup_seconds(cold=True), 2)
        result["startup_warm_s"] = round(kernel_startup_seconds(cold=False), 2)
    if args.json:
        print(json.dumps(result))
    else:
        print(f"omnibot, one robot, full dynamics + sensors: {ours:12,.0f} steps/s")
        if theirs:
            print(f"IR-SIM 2.12, one kinematic omni robot:       {theirs:12,.0f} steps/s")
            print(f"ratio omnibot / IR-SIM:                      {ours / theirs:12.2f}  (goal >= 10)")
        else:
            print("IR-SIM is not installed (make setup installs it); no ratio")
        print(f"omnibot, batch of 1000, Physics.step:        {batch_step:12,.0f} robot-steps/s")
        print(f"omnibot, batch of 1000, Physics.run, 1 core: {batch_one:12,.0f} robot-steps/s")
        print(f"omnibot, batch of 1000, Physics.run, all:    {batch:12,.0f} robot-steps/s")
        print(f"  the same, exact=False (lanes), 1 core:     {lanes_one:12,.0f} robot-steps/s")
        print(f"  the same, exact=False (lanes), all:        {lanes:12,.0f} robot-steps/s")
        print(f"batch of 1000, 1 thread, per CPU-second: exact {exact_cpu:12,.0f}, lanes {lanes_cpu:12,.0f}")
        for k, t in fleet.items():
            print(
                f"fleet of {k} with sonars, per step:           {t * 1e6:12.1f} us  ({t / fleet[1]:.2f} x one)"
            )
        if not args.no_startup:
            print(
                f"start-up to the first step (import + kernels): {result['startup_cold_s']:.2f} s with an "
                f"empty numba cache, {result['startup_warm_s']:.2f} s cached"
            )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
