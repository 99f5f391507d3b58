"""Axis MOVEs against where the idle wheels stand (issue 17; docs/calibration.md, *Courses 0 and 90*).

    python -m benchmarks.idle_phase [--robot nominal|acceptance] [--surface carpet|wood]
                                    [--calibration CAL.yaml] [--speeds 0.3,0.5] [--steps 8]
                                    [--span pitch|turn] [--seed 1]

On a course along a motor axis (omni4: 0 and 90 degrees) two wheels do not turn, and their rollers'
resistance depends on where each wheel stands (seed 000: "as much as twice"). This sets both idle
wheels of the course to the same angle, one step after another over one roller pitch (``--span
pitch``, default) or a whole wheel turn (``turn``: 33 steps, not a multiple of the roller
count, so that they fall on different roller phases), and drives a 1 m MOVE there on the simulator in
lockstep with the calibration's tables, once with its roller drag term and once without it. The
driven wheels stand where the MOVEs before left them (they turn through dozens of roller pitches in
one MOVE, so theirs averages out).

The tables are ``--calibration``'s (the surface's own section), or, without one, those of a
calibration run in-process first as ``omnibot calibrate`` runs it (``nominal``: the default plan and
check, seed ``--seed``) or as the acceptance test does (``acceptance``: wheel radius +5 %, torque
constants +10, -10, -10, +10 %, ``Plan(levels=7)``, check at 0.3, 0.6 and 0.9 m/s, seed 3),
its wheels started at angles drawn with seed ``--wheels N`` (0: all at 0), and its check's mean
error and axis MOVEs printed; ``--out DIR`` keeps that calibration's file. Prints one table per
course and speed: the distance error at each phase with and without the term, and the spread
(max - min) of each. A few seconds with ``--calibration``; a calibration first adds 1-3 minutes.
"""

from __future__ import annotations

import argparse
import math
import statistics
import tempfile
from collections.abc import Sequence
from pathlib import Path

from benchmarks.motor_model import lockstep_clients
from omnibot.calibration import (
    ACCEPTANCE,
    AccuracyPlan,
    Plan,
    SimTruth,
    load_calibration,
    perturbed_robot,
    session,
    write_calibration,
)
from omnibot.calibration.patterns import Geometry
from omnibot.calibration.runner import Runner
from omnibot.calibration.tap import TelemetryTap
from omnibot.calibration.verdict import mean_abs_error
from omnibot.client import RobotClient
from omnibot.errors import ConfigError
from omnibot.robot import CalibrationSpec, RobotDescription, load_robot
from omnibot.sim import SimDevice
from omnibot.transport import LockstepLink

LENGTH = 1.0
"""m of every MOVE."""


def robots(kind: str) -> tuple[RobotDescription, RobotDescription]:
    """(the description the firmware is built for, the robot the simulator drives)."""
    nominal = load_robot("omni4")
    return nominal, perturbed_robot(nominal, ACCEPTANCE) if kind == "acceptance" else nominal


def calibrate(kind: str, surface: str, seed: int, out: Path, wheels: int = 0) -> Path:
    """Calibrate in-process (see the module docstring), write the file to ``out`` and print the
    check's mean error and its axis MOVEs; the file's path."""
    nominal, true = robots(kind)
    open_client = lockstep_clients(nominal, true, seed, wheels)

    plan, accuracy = (
        (Plan(levels=7), AccuracyPlan(speeds=(0.3, 0.6, 0.9)))
        if kind == "acceptance"
        else (Plan(), AccuracyPlan())
    )
    result = session.calibrate(nominal, [surface], open_client, truth="sim", plan=plan, accuracy=accuracy)
    after = result.sessions[0].after or []
    axis = [r for r in after if r.kind == "move" and r.course_deg % 90 == 0 and r.speed <= 0.55]
    print(
        f"check ({kind}, {surface}, wheels {wheels}): mean abs error {100 * (mean_abs_error(after) or 0):.1f} %; "
        "axis MOVEs: "
        + ", ".join(f"{r.course_deg:g} at {r.speed:g} {100 * (r.error or 0):+.1f}" for r in axis)
    )
    return write_calibration(out / "calibration.yaml", result, "sim")


def sweep(
    kind: str,
    surface: str,
    spec: CalibrationSpec,
    courses: Sequence[float],
    speeds: Sequence[float],
    phases: Sequence[float],
    seed: int,
) -> dict[tuple[float, float, bool], list[float]]:
    """Distance error of a MOVE at each idle phase (fraction of a roller pitch, or of a turn with
    ``phases`` beyond 1), keyed by (course, speed, term on); one device for all of them."""
    nominal, true = robots(kind)
    geometry = Geometry.of(nominal)
    count = nominal.wheels[0].rollers.count
    off = spec.model_copy(update={"rollers": None})
    dev = SimDevice(nominal, true_robot=true, surface=surface, seed=seed)
    angles = dev.sim.physics.wheel_angle
    out: dict[tuple[float, float, bool], list[float]] = {}
    with RobotClient(LockstepLink(dev), nominal) as client:
        tap = TelemetryTap(client, nominal)
        tap.start()
        runner = Runner(client, nominal, SimTruth(dev.sim), tap)
        try:
            for on in (True, False):
                client.upload_calibration(spec if on else off)
                for course in courses:
                    idle = geometry.idle_wheels(course)
                    for speed in speeds:
                        errors = out.setdefault((course, speed, on), [])
                        for phase in phases:
                            for i in idle:  # the low-friction position is angle 0 (sim/physics.py)
                                angles[0, i] = 2.0 * math.pi * phase / count
                            r = runner.move("idle phase", LENGTH, speed, course, "idle phase")
                            d = r.truth.distance if r.truth is not None else None
                            errors.append(math.nan if d is None else d / LENGTH - 1.0)
        finally:
            runner.close()
            tap.stop()
    return out


def table(
    results: dict[tuple[float, float, bool], list[float]], phases: Sequence[float], count: int, span: str
) -> list[str]:
    """Markdown rows: per course and speed, the error at each phase with and without the term."""
    per = 1.0 if span == "pitch" else float(count)  # the header's unit: a pitch or a wheel turn
    head = " | ".join(f"{p / per:.3g}" for p in phases)
    unit = "a roller pitch" if span == "pitch" else "a wheel turn"
    lines = [
        f"(distance error %, both idle wheels at the angle given as a fraction of {unit}, 0: the least"
        " resistant roller position)",
        "",
        f"| course, m/s, term | {head} | spread | mean |",
        "|---|" + "---|" * (len(phases) + 2),
    ]
    for (course, speed, on), errs in sorted(
        results.items(), key=lambda kv: (kv[0][0], kv[0][1], not kv[0][2])
    ):
        cells = " | ".join(f"{100 * e:+.1f}" for e in errs)
        good = [e for e in errs if not math.isnan(e)]
        spread = 100 * (max(good) - min(good)) if good else math.nan
        mean = 100 * statistics.fmean(good) if good else math.nan
        lines.append(
            f"| {course:g}, {speed:g}, {'on' if on else 'off'} | {cells} | {spread:.1f} | {mean:+.1f} |"
        )
    return lines


def main(argv: list[str] | None = None) -> int:
    """Sweep the idle wheels' phase and print the table."""
    ap = argparse.ArgumentParser(prog="python -m benchmarks.idle_phase", description=__doc__.split("\n")[0])
    ap.add_argument("--robot", default="nominal", choices=["nominal", "acceptance"])
    ap.add_argument("--surface", default="carpet", choices=["wood", "carpet"])
    ap.add_argument("--calibration", type=Path, help="a calibration file (default: calibrate first)")
    ap.add_argument("--out", type=Path, help="directory to keep the in-process calibration's file in")
    ap.add_argument("--courses", default="0,90", help="courses, degrees (default 0,90)")
    ap.add_argument("--speeds", default="0.3,0.5", help="MOVE speeds, m/s (default 0.3,0.5)")
    ap.add_argument("--steps", type=int, help="phases over the span (default 8 over a pitch, 33 over a turn)")
    ap.add_argument("--span", default="pitch", choices=["pitch", "turn"])
    ap.add_argument("--seed", type=int, help="the simulator's seed (default: 1 nominal, 3 acceptance)")
    ap.add_argument("--wheels", type=int, default=0, help="seed of the wheels' start angles (0: all at 0)")
    args = ap.parse_args(argv)
    try:
        courses = [float(c) for c in args.courses.split(",")]
        speeds = [float(v) for v in args.speeds.split(",")]
    except ValueError:
        ap.error("--courses and --speeds take comma-separated numbers")
    steps = args.steps or (8 if args.span == "pitch" else 33)
    if steps < 2 or any(v <= 0 for v in speeds):
        ap.error("--steps must be at least 2 and every speed positive")
    seed = args.seed if args.seed is not None else (3 if args.robot == "acceptance" else 1)
    nominal, _ = robots(args.robot)
    count = nominal.wheels[0].rollers.count
    width = 1.0 if args.span == "pitch" else float(count)
    phases = [width * k / steps for k in range(steps)]
    path = args.calibration
    if path is None:
        out = args.out or Path(tempfile.mkdtemp(prefix="idle_phase_"))
        out.mkdir(parents=True, exist_ok=True)
        path = calibrate(args.robot, args.surface, seed, out, args.wheels)
        print(f"calibration: {path}")
    try:
        spec = load_calibration(path).for_surface(args.surface)
    except ConfigError as exc:
        ap.error(str(exc))
    results = sweep(args.robot, args.surface, spec, courses, speeds, phases, seed)
    print("\n".join(table(results, phases, count, args.span)))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
