"""Tracking metrics of a follow run: cross-track error, time against the minimum time, final error.

Cross-track error is the distance from the robot's position to the path (the whole polyline), at
every control tick between the start and the end of the run; RMS is over time. The positions are
the simulator's ground truth when the run has it, the robot's own estimate otherwise, and the
report says which (``source``).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from omnibot.control import MotionLimits, min_traversal_time, wrap
from omnibot.navigation.outcome import Tolerances
from omnibot.navigation.trace import FollowRun
from omnibot.robot import RobotDescription


def judge(report: dict[str, Any], tolerances: Tolerances) -> dict[str, Any]:
    """Decide ``report["completed"]`` from the follower's own verdict (and why it ended early, if it
    did) and the errors against ``tolerances``; ``report["failures"]`` says why not (the numbers)."""
    failures = []
    if report.get("failure"):
        failures.append(report["failure"])
    elif not report["follower_done"]:
        failures.append(f"the follower did not reach the end in {report['duration_s']:.1f} s")
    final, worst = report["final_error_m"], report["max_cross_track_m"]
    if not final <= tolerances.final:  # NaN fails too
        failures.append(f"final error {100 * final:.1f} cm > {100 * tolerances.final:.1f} cm")
    if not worst <= tolerances.cross_track:
        failures.append(f"max cross-track error {100 * worst:.1f} cm > {100 * tolerances.cross_track:.1f} cm")
    report["tolerances"] = {"final_m": tolerances.final, "cross_track_m": tolerances.cross_track}
    report["failures"] = failures
    report["completed"] = not failures
    return report


TRUTH = "simulator ground truth"
ODOMETRY = "odometry (the robot's own estimate; no ground truth on this link)"


def tracking_report(run: FollowRun, limits: MotionLimits) -> dict[str, Any]:
    """The report of a run (JSON-ready; lengths in m, times in s, angles in rad).

    ``limits`` are the robot's physical limits (with the run's speed cap): ``min_time_s`` is the
    time-optimal traversal under them, the bound no follower can beat.
    """
    a = run.arrays()
    use_truth = run.has_truth
    poses = a["truth"] if use_truth else a["estimate"]
    path = run.path
    if len(poses):
        dist, s = path.nearest(poses[:, :2])
        heading_err = np.array(
            [wrap(th - path.heading_at(si)) for th, si in zip(poses[:, 2], s, strict=True)]
        )
    else:
        dist = s = heading_err = np.zeros(0)
    final = run.final_truth if use_truth else run.final_estimate
    end = path.end
    min_time = min_traversal_time(path, limits)
    report: dict[str, Any] = {
        "source": TRUTH if use_truth else ODOMETRY,
        "follower": run.follower,
        "estimator": run.estimator,
        "follower_done": run.completed,
        "completed": run.completed,
        "failure": run.failure,
        "rms_cross_track_m": float(np.sqrt(np.mean(dist**2))) if len(dist) else math.nan,
        "max_cross_track_m": float(dist.max()) if len(dist) else math.nan,
        "rms_heading_error_rad": float(np.sqrt(np.mean(heading_err**2))) if len(dist) else math.nan,
        "duration_s": run.duration,
        "min_time_s": min_time,
        "time_ratio": run.duration / min_time if min_time > 0 else math.nan,
        "final_error_m": math.hypot(final.x - end[0], final.y - end[1]) if final else math.nan,
        "final_heading_error_rad": wrap(final.theta - end[2]) if final else math.nan,
        "path_length_m": path.length,
        "samples": len(dist),
        "warnings": list(run.warnings),
    }
    if use_truth and run.final_estimate is not None and run.final_truth is not None:
        fe, ft = run.final_estimate, run.final_truth
        report["estimate_error_m"] = math.hypot(fe.x - ft.x, fe.y - ft.y)
    return report


def follow_report(
    run: FollowRun,
    robot: RobotDescription,
    tolerances: Tolerances,
    *,
    speed: float | None = None,
    floor: str | None = None,
) -> dict[str, Any]:
    """The judged report of a run (:func:`tracking_report`, then :func:`judge`), as ``omnibot follow``
    and every follow on the runtime (``run --follow``, the page's Repeat, ROS 2's path) give it:
    ``speed`` the run's speed cap, ``floor`` the floor its minimum time is measured on."""
    limits = MotionLimits.from_robot(robot, speed, surface=floor)
    report = judge(tracking_report(run, limits), tolerances)
    report["robot"] = robot.name
    if speed is not None:
        report["speed_cap_m_s"] = speed
    return report


def error_along_path(run: FollowRun) -> tuple[np.ndarray, np.ndarray]:
    """(arc length, cross-track distance) of every recorded position (truth if there is any)."""
    a = run.arrays()
    poses = a["truth"] if run.has_truth else a["estimate"]
    if not len(poses):
        return np.zeros(0), np.zeros(0)
    dist, s = run.path.nearest(poses[:, :2])
    return s, dist
