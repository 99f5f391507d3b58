"""The firmware's wheel-speed loop on steps and ramps: how far past the asked speed the wheels and the
body go (issue 17: mecanum4 drove over the asked speed on carpet).

    python -m benchmarks.speed_loop [--robots mecanum4,omni4,omni3] [--surfaces carpet,wood] [--speed M/S]

Each run: the simulator with the MicroPython firmware in lockstep, MODE 2 (the wheel-speed loop),
then VEL commands every 20 ms as a host sends them, either a ramp at 1.4 m/s^2 (the tracking
profile's acceleration) up to the speed asked, without and with its planned acceleration (VEL's A,
protocol version 3: the firmware feeds its torque forward), or a step to it, held 1.5 s, on courses
0, 45 (44.5: 0.8 m/s on 45 degrees rounds past speed_max in whole cm/s) and 90 degrees, at the
robot's speed (mecanum4 and omni4 0.8 m/s, omni3 3 m/s) or ``--speed``. Reported:

* wheel: the largest ``|wheel speed| / |its final target|`` of the wheels that drive (target at
  least half the largest), after the target reached its final value, minus 1;
* body: the body's largest speed over the speed it settles at (the mean of the last 0.5 s), minus 1,
  and over the speed asked (on carpet at 45 degrees a mecanum body settles above what its wheels'
  speeds say: roller creep, not the loop);
* rise: the time the body first reaches 98 % of its settled speed.

A few seconds of CPU per robot and floor; deterministic (seed 1).

``--feedforward`` prints instead what the loop's integral holds once the speed is steady: VEL at
0.3 m/s (``--speed``) on courses 0, 45 and 90 degrees and a rotation at 1 rad/s (as the
speed-accuracy benchmark asks), refreshed every 50 ms for 2 s, then ``ki * integral / feedforward`` of the wheel driven
hardest: the share of the power the feedforward gets wrong on that floor, which the integral has to
learn after every start. ``--calibration CAL.yaml`` (one robot's file from ``omnibot calibrate``)
uploads its floor's tables first, as the front ends' ``--calibration`` does.
"""

from __future__ import annotations

import argparse
import math
from dataclasses import dataclass

from omnibot.calibration import floor_calibration
from omnibot.client import commands
from omnibot.protocol import text
from omnibot.sim import SimDevice

CYCLE = 0.02  # s between VEL commands
ACCEL = 1.4  # m/s^2, the tracking profile's
HOLD = 1.5  # s at the asked speed
SPEEDS = {"mecanum4": 0.8, "omni4": 0.8, "omni3": 3.0}
COURSES = (0.0, 44.5, 90.0)


@dataclass
class Result:
    """One run's overshoots (fractions) and rise time (s)."""

    wheel: float
    body: float
    body_asked: float
    rise: float


def run(
    robot: str, surface: str, course: float, speed: float, ramp: bool, seed: int = 1, plan: bool = False
) -> Result:
    """Drive one step or ramp on the firmware's closed loop and measure it; ``plan``: a ramp's VELs
    carry its acceleration (A, cm/s^2) until its last."""
    dev = SimDevice(robot, surface=surface, seed=seed)

    def send(line: str) -> None:
        dev.command(line, CYCLE)

    send("MODE,2")
    c, s = math.cos(math.radians(course)), math.sin(math.radians(course))
    ramp_time = speed / ACCEL if ramp else 0.0
    target = dev.controller.executor._target  # the loop's wheel targets, rad/s
    t = 0.0
    wheel_peak = [0.0] * len(target)
    final: list[float] = []
    body: list[tuple[float, float]] = []
    while t < ramp_time + HOLD:
        v = min(speed, ACCEL * (t + CYCLE)) if ramp else speed
        a = f",{round(ACCEL * 100)}" if plan and ramp and v < speed else ""
        send(f"VEL,{int(v * c * 100)},{int(v * s * 100)},0,200{a}")
        t += CYCLE
        tw = dev.sim.twist
        body.append((t, math.hypot(tw.vx, tw.vy)))
        if v == speed:
            final = final or list(target)
            for i, w in enumerate(dev.sim.wheel_speeds):
                wheel_peak[i] = max(wheel_peak[i], abs(w))
    send("STOP")
    top = max(abs(f) for f in final)
    wheel = max(p / abs(f) for p, f in zip(wheel_peak, final, strict=True) if abs(f) >= 0.5 * top)
    tail = [b for tb, b in body if tb > t - 0.5]
    settled = sum(tail) / len(tail)
    peak = max(b for _, b in body)
    rise = next((tb for tb, b in body if b >= 0.98 * settled), math.nan)
    return Result(wheel - 1.0, peak / settled - 1.0, peak / speed - 1.0, rise)


def feedforward_error(
    robot: str,
    surface: str,
    course: float | None,
    seed: int = 1,
    calibration: str | None = None,
    speed: float = 0.3,
) -> float:
    """The integral's share of the feedforward power (``ki * integral / ff``) of the wheel driven
    hardest after 2 s at ``speed`` m/s on ``course`` (None: turning at 1 rad/s in place);
    ``calibration``: a calibration file whose floor's tables are uploaded first (CAL)."""
    dev = SimDevice(robot, surface=surface, seed=seed)
    if calibration is not None:
        tables, _ = floor_calibration(calibration, dev.robot, surface)
        for cal in commands.calibration(tables, len(dev.robot.wheels)) if tables is not None else []:
            dev.command(text.encode(cal).decode().strip(), 0.001)
    dev.command("MODE,2", CYCLE)
    if course is None:
        line = "VEL,0,0,57,200"
    else:
        c, s = math.cos(math.radians(course)), math.sin(math.radians(course))
        line = f"VEL,{round(100 * speed * c)},{round(100 * speed * s)},0,200"
    for _ in range(40):
        dev.command(line, 0.05)
    ex = dev.controller.executor
    loop = ex.speedctl
    target = ex._target
    k = max(range(len(target)), key=lambda i: abs(target[i]))
    return float(loop.ki * loop._integ[k] / ex._ff[k])


def main() -> None:
    """Print one markdown table: every robot, floor, course, ramp and step (``--feedforward``: the
    feedforward's error at a steady speed)."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--robots", default="mecanum4")
    ap.add_argument("--surfaces", default="carpet,wood")
    ap.add_argument("--feedforward", action="store_true", help="the integral's share at a steady speed")
    ap.add_argument("--calibration", metavar="CAL.yaml", help="--feedforward: upload this file's floor first")
    ap.add_argument("--speed", type=float, help="m/s (default: 0.3 with --feedforward, else the robot's)")
    args = ap.parse_args()
    if args.feedforward:
        print("| robot | floor | 0 deg | 45 deg | 90 deg | rotation |")
        print("|---|---|---|---|---|---|")
        for robot in args.robots.split(","):
            for surface in args.surfaces.split(","):
                shares = [
                    feedforward_error(
                        robot, surface, c, calibration=args.calibration, speed=args.speed or 0.3
                    )
                    for c in (0.0, 45.0, 90.0, None)
                ]
                print(f"| {robot} | {surface} | " + " | ".join(f"{100 * x:+.0f} %" for x in shares) + " |")
        return
    print(
        "| robot | floor | course (deg) | input | wheel overshoot | body over settled | body over asked | rise (s) |"
    )
    print("|---|---|---|---|---|---|---|---|")
    for robot in args.robots.split(","):
        speed = args.speed or SPEEDS.get(robot, 0.5)
        for surface in args.surfaces.split(","):
            for course in COURSES:
                for ramp, plan in ((True, False), (True, True), (False, False)):
                    r = run(robot, surface, course, speed, ramp, plan=plan)
                    kind = f"ramp {ACCEL} m/s^2 to {speed}" if ramp else f"step to {speed}"
                    kind += " with A" if plan else ""
                    print(
                        f"| {robot} | {surface} | {course:g} | {kind} | {100 * r.wheel:.0f} % "
                        f"| {100 * r.body:.0f} % | {100 * r.body_asked:+.0f} % | {r.rise:.2f} |",
                        flush=True,
                    )


if __name__ == "__main__":
    main()
