"""A fitted wheel slip on courses and speeds other than its own runs': straight runs on the simulator.

Run: ``python -m benchmarks.slip_courses --robot mecanum4 [--calibration CAL.yaml] [--speed 0.4]
[--distance 1.0] [--courses 0 15 90 ...]``. Without ``--calibration`` the slip is fitted first as
``omnibot calibrate`` fits it (:func:`~omnibot.navigation.slipcal.simulate_slip_calibration` at the
calibration's speed, :data:`CALIBRATION_SEED`). Then the robot drives one straight run per course
(body frame, heading held, from rest to rest, the same runs as the fit's but at the given speed and
distance) and each run's encoder displacement is compared with the simulator's truth: along and
across the course, in % of the distance, raw and with the fitted slip taken out, and the share the
correction moved along the body's x and y. So whether the fit over- or under-corrects a route's
courses and speeds is measured run by run, not inferred from a route's end error.
"""

from __future__ import annotations

import argparse
import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from omnibot.calibration import load_calibration
from omnibot.calibration.slip import slip_speed
from omnibot.estimation import SlipLeg, SlipParameters, SlipProbe, leg_residual
from omnibot.navigation import Navigator, simulated_client
from omnibot.navigation.slipcal import SimulatorTruth, drive_run, simulate_slip_calibration
from omnibot.robot import RobotDescription, load_robot
from omnibot.robot.kinematics import body_to_world

CALIBRATION_SEED = 7
"""The simulator's seed of the fit (``benchmarks.slam_bench``'s calibration seed)."""
RUN_SEED = 11
"""The simulator's seed of the measured runs: not the fit's."""
COURSES = (0.0, 15.0, 20.0, 25.0, 45.0, 90.0, 165.0, 180.0)
"""Degrees: the long corridor's route's courses (the axis, its zigzag's diagonals, its strafes)."""
SETTLE = 0.4
"""s standing before and after each run."""
ACCEL = 1.0
"""m/s^2 of each run's ramps (the fit's)."""


@dataclass(frozen=True)
class CourseError:
    """One run's encoder error, % of the distance driven: along and across the course, raw and
    corrected, and the correction's body x and y."""

    course_deg: float
    distance: float
    raw: tuple[float, float]
    corrected: tuple[float, float]
    correction_xy: tuple[float, float]


def course_runs(
    robot: RobotDescription, surface: str, courses: Sequence[float], speed: float, distance: float, seed: int
) -> list[tuple[float, SlipLeg]]:
    """One straight run per course (degrees, body frame) on the lockstep simulator, each with its
    true displacement (the estimator's frame)."""
    out: list[tuple[float, SlipLeg]] = []
    with simulated_client(robot, surface=surface, seed=seed) as client:
        nav = Navigator(client, robot)
        probe = SlipProbe(robot)
        try:
            nav.prepare()
            truth = SimulatorTruth(nav)
            nav.runtime.telemetry_hooks.append(probe.update)
            for deg in courses:
                client.sleep(SETTLE)
                mark, start = truth.start(), probe.mark()
                drive_run(nav, math.radians(deg), speed, distance, ACCEL)
                client.sleep(SETTLE)
                disp = truth.displacement(mark, math.radians(deg))
                if disp is None:
                    raise RuntimeError("the simulator gave no truth")
                x, y, _ = body_to_world((*disp, 0.0), probe.heading(start))
                out.append((deg, probe.leg(start, (float(x), float(y)))))
        finally:
            nav.close()
    return out


def course_error(robot: RobotDescription, deg: float, leg: SlipLeg, params: SlipParameters) -> CourseError:
    """A run's errors along and across its course (the world frame of its start heading)."""
    heading = float(leg.headings[0])
    along = np.array([math.cos(heading + math.radians(deg)), math.sin(heading + math.radians(deg))])
    across = np.array([-along[1], along[0]])
    dist = max(float(np.hypot(*leg.true_disp)), 1e-9)
    raw, fixed = leg_residual(leg), leg_residual(leg, params, robot)
    moved = raw - fixed
    c, s = math.cos(heading), math.sin(heading)
    body = (c * moved[0] + s * moved[1], -s * moved[0] + c * moved[1])

    def pct(v: np.ndarray) -> tuple[float, float]:
        return (100.0 * float(v @ along) / dist, 100.0 * float(v @ across) / dist)

    return CourseError(deg, dist, pct(raw), pct(fixed), (100.0 * body[0] / dist, 100.0 * body[1] / dist))


def fitted(robot: RobotDescription, surface: str, calibration: Path | None) -> SlipParameters:
    """The slip of ``calibration`` on ``surface``, or fitted on the simulator as ``omnibot calibrate`` does."""
    if calibration is not None:
        return load_calibration(calibration).slip_for(surface)
    return simulate_slip_calibration(robot, surface, seed=CALIBRATION_SEED, speed=slip_speed(robot)).params


def _row(e: CourseError) -> str:
    return (
        f"| {e.course_deg:.1f} | {e.distance:.3f} m | {e.raw[0]:+.3f} / {e.raw[1]:+.3f} % | "
        f"{e.corrected[0]:+.3f} / {e.corrected[1]:+.3f} % | {e.correction_xy[0]:+.3f} / {e.correction_xy[1]:+.3f} % |"
    )


def main(argv: Sequence[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m benchmarks.slip_courses", description=__doc__.split("\n")[0])
    p.add_argument("--robot", default="mecanum4")
    p.add_argument("--surface", default="wood")
    p.add_argument("--calibration", type=Path, help="calibration file (default: fit on the simulator)")
    p.add_argument("--speed", type=float, default=0.4, help="m/s (default 0.4: the SLAM bench's)")
    p.add_argument("--distance", type=float, default=1.0, help="m per run (default 1)")
    p.add_argument("--courses", type=float, nargs="+", default=list(COURSES), help="degrees, body frame")
    p.add_argument("--seed", type=int, default=RUN_SEED)
    args = p.parse_args(argv)
    robot = load_robot(args.robot)
    params = fitted(robot, args.surface, args.calibration)
    print(
        f"{args.robot} on {args.surface}: {params.as_dict()}; runs of {args.distance} m at {args.speed} m/s"
    )
    print(
        "| course (deg) | true distance | raw along / across | corrected along / across | correction body x / y |"
    )
    print("|---|---|---|---|---|")
    for deg, leg in course_runs(robot, args.surface, args.courses, args.speed, args.distance, args.seed):
        print(_row(course_error(robot, deg, leg, params)), flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
