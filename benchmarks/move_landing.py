"""Where MOVE, ROTATE and DELTA land, from the simulator's truth, open loop and on the wheel-speed loop
(issue 24: mecanum4 ``MOVE,100,10,0,0`` went 2.14 m and said OK; seed 000's circle came out 18 cm
across where the commands ask for 23).

    python -m benchmarks.move_landing [--robots omni4,omni3,mecanum4] [--surfaces wood,carpet]
                                      [--modes 0,2,2s] [--detail] [--calibration CAL.yaml]

Each run: a fresh simulator with the firmware in lockstep (seed 1, the preset's calibration, or with
``--calibration`` the file's tables of the floor, as ``omnibot calibrate`` wrote them), the
MODE (0: open loop, seed 000's timeline; 2: the wheel-speed loop; ``2s``: 2 with the floor's creep
coefficients, CAL table 9, fitted by ``omnibot calibrate``'s slip runs on the simulator, seed 1000),
then one command line, until IDLE and 1 s after it (the coast). Runs:

* MOVEs of 0.3 and 1 m at three speeds per robot (:data:`SPEEDS`) on courses 0, 45, 90, 135 and
  180 degrees: the error is the true displacement along the course over the distance asked, less 1
  (and how far off the course's line it ends, in cm);
* ROTATE 90 and 360 degrees at 90 and 180 degrees/s: the true turn over the angle asked, less 1;
* seed 000's circle, ``MOVE,2,40,0,0;DELTA,0,0,10,0,36``: 37 moves of 2 cm, a 36-gon 22.86 cm
  across (twice its apothem) and 74 cm of path; the error is the diameter of the circle that fits
  the truth's trail until IDLE best over 22.86 cm, less 1, with how round the trail is (its largest
  less its smallest distance from that circle's centre), its length (summed every 10 ms) and how
  far from where the commands end (2 cm along course 0 from the start) it stood after the coast.

Also the time from the command to IDLE. One row per robot, floor and mode (the worst MOVE named);
``--detail`` adds every run. Deterministic; 45 s of CPU for every robot, floor and the three modes.
"""

from __future__ import annotations

import argparse
import functools
import itertools
import math
from dataclasses import dataclass

import numpy as np

from omnibot.calibration import apply_calibration, floor_calibration
from omnibot.navigation.slipcal import simulate_slip_calibration
from omnibot.robot import RobotDescription, load_robot
from omnibot.sim import SimDevice

SPEEDS = {"omni4": (30, 60, 90), "omni3": (10, 30, 100), "mecanum4": (10, 30, 60)}
"""cm/s of the MOVEs per robot: from its slowest (omni4: 30, mecanum4: 10) up the range."""
LENGTHS = (30, 100)
COURSES = (0, 45, 90, 135, 180)
ROTATES = ((90, 90), (360, 180))
CIRCLE = "MOVE,2,40,0,0;DELTA,0,0,10,0,36"
CIRCLE_ACROSS = 2.0 * 1.0 / math.tan(math.radians(5.0))  # cm: twice the apothem of a 36-gon of 2 cm sides
CIRCLE_PATH = 74.0  # cm
CALIBRATION_SEED = 1000
"""Simulator seed of the slip calibration runs (not the seed of the runs it is used in)."""
SETTLE = 1.0  # s after IDLE
LIMIT = 30.0  # s at most per run


@dataclass
class Run:
    """One command line and what the truth saw."""

    kind: str  # "MOVE", "ROTATE", "DELTA"
    command: str
    error: float  # fraction: achieved / asked - 1
    idle: float  # s from the command to IDLE (nan: none)
    extra: str = ""
    across: float = 0.0  # m off the course (a MOVE)


@functools.cache
def floor_slip(robot: str, surface: str) -> list[float]:
    """The floor's creep coefficients for the firmware (``slip``: roll, combined, scale), from
    ``omnibot calibrate``'s slip runs on the simulator (seed :data:`CALIBRATION_SEED`)."""
    description = load_robot(robot)
    speed = min(0.8, 0.5 * (description.limits.speed_min + description.limits.speed_max))
    p = simulate_slip_calibration(description, surface, seed=CALIBRATION_SEED, speed=speed).params
    return [p.roll, p.combined, p.scale, p.ramp]


@functools.cache
def firmware_robot(robot: str, surface: str, calibration: str | None) -> RobotDescription:
    """The description the firmware is built for: the preset, with ``calibration``'s tables of the
    floor (a calibration file) when given."""
    description = load_robot(robot)
    if calibration is None:
        return description
    tables, _ = floor_calibration(calibration, description, surface)
    return apply_calibration(description, tables) if tables is not None else description


def drive(
    robot: str, surface: str, mode: str, command: str, seed: int = 1, calibration: str | None = None
) -> tuple[SimDevice, list[tuple[float, float, float]], float]:
    """Run ``command`` in MODE ``mode`` (``2s``: 2 with the floor's creep coefficients) until IDLE and
    :data:`SETTLE` after; the truth trail (x, y, theta every 10 ms, the first the start) and the
    time to IDLE."""
    overrides = {"slip": floor_slip(robot, surface)} if mode.endswith("s") else None
    built = firmware_robot(robot, surface, calibration)
    true = load_robot(robot) if calibration is not None else None
    dev = SimDevice(built, surface=surface, seed=seed, firmware_overrides=overrides, true_robot=true)
    dev.receive(f"MODE,{mode.rstrip('s')}\n".encode())
    for _ in range(5):
        dev.step()
    dev.transmit()
    every = max(1, round(0.01 / dev.tick))
    p = dev.sim.pose
    trail = [(p.x, p.y, p.theta)]
    dev.receive((command + "\n").encode())
    out = b""
    t0 = dev.time
    idle = math.nan
    k = 0
    while dev.time - t0 < LIMIT:
        dev.step()
        k += 1
        if k % every == 0:
            p = dev.sim.pose
            trail.append((p.x, p.y, p.theta))
            out += dev.transmit()
            if math.isnan(idle) and b"IDLE" in out:
                idle = dev.time - t0
            if not math.isnan(idle) and dev.time - t0 - idle >= SETTLE:
                break
    return dev, trail, idle


def move(
    robot: str, surface: str, mode: str, length: int, speed: int, course: int, calibration: str | None = None
) -> Run:
    """A MOVE's error along its course (the body's start heading)."""
    command = f"MOVE,{length},{speed},{course},0"
    _, trail, idle = drive(robot, surface, mode, command, calibration=calibration)
    x0, y0, th0 = trail[0]
    x1, y1, _ = trail[-1]
    a = th0 + math.radians(course)
    along = (x1 - x0) * math.cos(a) + (y1 - y0) * math.sin(a)
    across = -(x1 - x0) * math.sin(a) + (y1 - y0) * math.cos(a)
    return Run(
        "MOVE", command, along * 100.0 / length - 1.0, idle, f"off course {across * 100:+.1f} cm", across
    )


def rotate(robot: str, surface: str, mode: str, angle: int, rate: int, calibration: str | None = None) -> Run:
    """A ROTATE's error in angle."""
    command = f"ROTATE,{angle},{rate}"
    _, trail, idle = drive(robot, surface, mode, command, calibration=calibration)
    turned = 0.0
    for (_, _, a), (_, _, b) in itertools.pairwise(trail):
        turned += (b - a + math.pi) % (2.0 * math.pi) - math.pi
    return Run("ROTATE", command, math.degrees(turned) / angle - 1.0, idle)


def circle(robot: str, surface: str, mode: str, calibration: str | None = None) -> Run:
    """Seed 000's circle: the diameter of the circle that fits the truth's trail best (least squares,
    until IDLE) against the 36-gon's, its roundness (largest less smallest radius) and its path."""
    _, trail, idle = drive(robot, surface, mode, CIRCLE, calibration=calibration)
    moving = trail[: max(3, round(idle / 0.01) + 1)] if not math.isnan(idle) else trail
    xy = np.array([(x, y) for x, y, _ in moving])
    a = np.column_stack((2.0 * xy, np.ones(len(xy))))
    cx, cy, c = np.linalg.lstsq(a, (xy * xy).sum(axis=1), rcond=None)[0]
    radius = math.sqrt(c + cx * cx + cy * cy)
    radii = np.hypot(xy[:, 0] - cx, xy[:, 1] - cy)
    path = float(np.hypot(*np.diff(xy, axis=0).T).sum())
    size = 200.0 * radius
    x0, y0, th0 = trail[0]
    x1, y1, _ = trail[-1]
    end = math.hypot(x1 - x0 - 0.02 * math.cos(th0), y1 - y0 - 0.02 * math.sin(th0))  # 2 cm on course 0
    return Run(
        "DELTA",
        CIRCLE,
        size / CIRCLE_ACROSS - 1.0,
        idle,
        f"{size:.1f} cm (asked {CIRCLE_ACROSS:.1f}), round within {100 * float(radii.max() - radii.min()):.1f} cm, "
        f"path {path * 100:.1f} cm (asked {CIRCLE_PATH:.0f}), ends {100 * end:.1f} cm off",
    )


def runs(robot: str, surface: str, mode: str, calibration: str | None = None) -> list[Run]:
    """Every run of one robot, floor and mode (the firmware with ``calibration``'s tables of the floor)."""
    out = [
        move(robot, surface, mode, length, speed, course, calibration)
        for length in LENGTHS
        for speed in SPEEDS[robot]
        for course in COURSES
    ]
    out += [rotate(robot, surface, mode, a, f, calibration) for a, f in ROTATES]
    out.append(circle(robot, surface, mode, calibration))
    return out


def pct(x: float) -> str:
    """A fraction as a signed per cent."""
    return f"{100.0 * x:+.1f} %"


def main(argv: list[str] | None = None) -> None:
    """Print the summary table (and with ``--detail`` every run)."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--robots", default="omni4,omni3,mecanum4")
    ap.add_argument("--surfaces", default="wood,carpet")
    ap.add_argument(
        "--modes", default="0,2,2s", help="MODEs: 0 open loop, 2 closed, 2s closed with the floor's creep"
    )
    ap.add_argument("--detail", action="store_true", help="every run, not only the summary")
    ap.add_argument("--calibration", help="a calibration file: the firmware gets its tables of each floor")
    args = ap.parse_args(argv)
    print(
        "| robot | floor | MODE | MOVE mean abs | MOVE worst | within 2 % | off course at most | ROTATE 90 / 360 "
        "| circle diameter | round within | circle path | circle ends off |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    detail: list[str] = []
    for robot in args.robots.split(","):
        for surface in args.surfaces.split(","):
            for mode in args.modes.split(","):
                rs = runs(robot, surface, mode, args.calibration)
                moves = [r for r in rs if r.kind == "MOVE"]
                worst = max(moves, key=lambda r: abs(r.error))
                mean = sum(abs(r.error) for r in moves) / len(moves)
                within = sum(abs(r.error) <= 0.02 for r in moves)
                off = 100.0 * max(abs(r.across) for r in moves)
                rot = " / ".join(pct(r.error) for r in rs if r.kind == "ROTATE")
                (circ,) = (r for r in rs if r.kind == "DELTA")
                size, _, rest = circ.extra.partition(", round within ")
                roundness, _, rest = rest.partition(", path ")
                path, _, end = rest.partition(", ends ")
                print(
                    f"| {robot} | {surface} | {mode} | {100 * mean:.1f} % | {pct(worst.error)} "
                    f"`{worst.command}` | {within}/{len(moves)} | {off:.1f} cm | {rot} | {size} | {roundness} | {path} "
                    f"| {end.replace(' off', '')} |",
                    flush=True,
                )
                detail += [
                    f"| {robot} | {surface} | {mode} | `{r.command}` | {pct(r.error)} | {r.idle:.2f} | {r.extra} |"
                    for r in rs
                ]
    if args.detail:
        print()
        print("| robot | floor | MODE | command | error | IDLE after (s) | |")
        print("|---|---|---|---|---|---|---|")
        for line in detail:
            print(line)


if __name__ == "__main__":
    main()
