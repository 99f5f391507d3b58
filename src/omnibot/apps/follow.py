"""``omnibot follow``: repeat a path file with a path follower, report how it tracked (and, asked,
write the report, the plot and the ground truth); exit status 1 when the run was outside its
tolerances (:class:`~omnibot.navigation.metrics.Tolerances`). The robot it drives:
:func:`omnibot.apps.teach.robot_client`.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path as FsPath
from typing import TYPE_CHECKING, Any

from omnibot.apps.teach import robot_client
from omnibot.cliargs import (
    DeprecatedAlias,
    add_off_path_option,
    add_robot_options,
    add_wheel_loop_option,
    check_distinct,
    check_plot,
    check_sim_options,
    off_path_options,
    output_dir,
    positive,
    recording_of,
    seed_of,
    use_calibration,
)
from omnibot.errors import ConfigError
from omnibot.outputs import check_writable, made_directory

if TYPE_CHECKING:
    from omnibot.navigation import Tolerances


def run(args: argparse.Namespace) -> int:
    """Run ``omnibot follow``: follow a path file and report tracking; the exit status (1 when the run
    did not complete, its failures printed)."""
    from omnibot.control import read_path
    from omnibot.motion import Pose2D
    from omnibot.navigation import FollowOptions, follow_path, summary, verdict
    from omnibot.progress import progress_bar

    check_sim_options(args, allowed=("surface",))
    path = read_path(args.path)
    _check_follower_and_estimator(args)
    rate = positive(args.rate, "--rate")
    speed = positive(args.speed, "--speed") if args.speed is not None else None
    tolerances = _tolerances(args)
    follower_options = off_path_options(args)
    targets = _follow_targets(args)
    metres = "{l_bar}{bar}| {n:.2f}/{total:.2f} m [{elapsed}<{remaining}]"
    with (
        robot_client(args, start=Pose2D(*path.start)) as (client, robot),
        progress_bar(f"follow {FsPath(args.path).name}", path.length, bar_format=metres) as bar,
    ):
        floor = use_calibration(args, client, robot)  # the floor's tables and creep, uploaded
        slip = floor.params if floor is not None else None
        options = FollowOptions(
            follower=args.follower,
            follower_options=follower_options,
            speed=speed,
            estimator=args.estimator,
            rate=rate,
            wheel_loop=not args.open_loop,
            calibrate_gyro=args.calibrate_gyro,
            slip=slip,
            floor=args.surface,  # plan within what this floor lets the motors give
            tolerances=tolerances,
            progress=bar,
            recording=recording_of(args),
        )
        run, report, _ = follow_path(client, robot, path, options)
    surface = args.surface or "the world's floor"
    report["path_file"] = str(args.path)
    report["link"] = args.port or f"sim://{robot.name} (lockstep, surface {surface}, seed {seed_of(args)})"
    if options.slip is not None:
        report["slip_calibration"] = {"file": str(args.calibration), **options.slip.as_dict()}
    print(f"omnibot follow: {robot.name}, {args.follower}, {len(path)} points, {path.length:.2f} m")
    print(f"  {summary(report)}")
    for text in report["warnings"]:
        print(f"  warning: {text}")
    _write_follow_outputs(args, targets, run, report, robot.name)
    print(f"omnibot follow: {verdict(report)}")
    return 0 if report["completed"] else 1


def _check_follower_and_estimator(args: argparse.Namespace) -> None:
    """ConfigError unless ``--follower`` and ``--estimator`` name ones that exist."""
    from omnibot.control import follower_names
    from omnibot.estimation import ESTIMATORS

    names = follower_names()
    if args.follower not in names:
        raise ConfigError(
            f"unknown follower '{args.follower}'; expected one of: {', '.join(names)}", key="--follower"
        )
    if args.estimator not in ESTIMATORS:
        raise ConfigError(
            f"unknown estimator '{args.estimator}'; expected one of: {', '.join(ESTIMATORS)}",
            key="--estimator",
        )


def _tolerances(args: argparse.Namespace) -> Tolerances:
    """The run's tolerances from ``--final-tolerance`` and ``--cross-track-tolerance``."""
    from omnibot.navigation import Tolerances

    return Tolerances(
        final=positive(args.final_tolerance, "--final-tolerance"),
        cross_track=positive(args.cross_track_tolerance, "--cross-track-tolerance"),
    )


def _follow_targets(args: argparse.Namespace) -> dict[str, FsPath | None]:
    """The files ``omnibot follow`` writes (``truth``, ``report``, ``plot``; None: not written): each
    given, else in ``--out DIR``; checked writable and distinct from the inputs and ``--log``."""
    out = _out_dir(args)
    for flag in ("truth", "report"):
        check_writable(getattr(args, flag), f"--{flag}")
    check_plot(args.plot, "--plot")
    targets = {
        "truth": _target(args.truth, out, "follow_truth.csv"),
        "report": _target(args.report, out, "follow_report.json"),
        "plot": _target(args.plot, out, "follow_plot.png"),
    }
    check_distinct(
        [*((f"--{k}" if getattr(args, k) else "--out", v) for k, v in targets.items()), ("--log", args.log)],
        [("PATH", args.path), ("--calibration", args.calibration)],
    )
    return targets


def _write_follow_outputs(
    args: argparse.Namespace, targets: dict[str, FsPath | None], run: Any, report: dict[str, Any], robot: str
) -> None:
    """Write the ground truth, the report and the plot where :func:`_follow_targets` put them."""
    if args.out:
        made_directory(FsPath(args.out), "--out")
    if targets["truth"] is not None:
        if run.has_truth:
            _write_truth(run, targets["truth"])
            print(f"  truth: {targets['truth']}")
        elif args.truth:
            raise ConfigError("no ground truth on this link (only the simulator has one)", key="--truth")
    if targets["report"] is not None:
        _write(targets["report"], json.dumps(report, indent=2) + "\n", "--report")
        print(f"  report: {targets['report']}")
    if targets["plot"] is not None:
        from omnibot.navigation import plot_run

        try:
            plot_run(run, str(targets["plot"]), title=f"{robot}: {args.follower} on {FsPath(args.path).name}")
        except OSError as exc:
            raise ConfigError(
                f"cannot write {targets['plot']}: {exc.strerror or exc}", key="--plot"
            ) from None
        print(f"  plot: {targets['plot']}")


def _out_dir(args: argparse.Namespace) -> FsPath | None:
    """``--out DIR`` checked (made by :func:`_write_follow_outputs` with its first file), or None."""
    return output_dir(args.out) if args.out else None


def _target(given: str | None, out: FsPath | None, name: str) -> FsPath | None:
    """An output file: the one given, else ``name`` in ``--out DIR``, else none."""
    if given:
        return FsPath(given)
    return out / name if out is not None else None


def _write(target: FsPath, text: str, flag: str) -> None:
    try:
        target.write_text(text, encoding="utf-8")
    except OSError as exc:
        raise ConfigError(f"cannot write {target}: {exc.strerror or exc}", key=flag) from None


def _write_truth(run: Any, target: FsPath) -> None:
    rows = ["t,x,y,theta"]
    t0 = run.t[0] if run.t else 0.0
    for t, (x, y, th) in zip(run.t, run.truth, strict=False):
        rows.append(f"{t - t0:.3f},{x:.5f},{y:.5f},{th:.5f}")
    _write(target, "\n".join(rows) + "\n", "--truth")


def add_arguments(p: argparse.ArgumentParser) -> None:
    """The ``omnibot follow`` options: path file, follower, robot or port, estimator and tolerances."""
    p.add_argument(
        "path",
        help="path file: CSV t,x,y,theta[,v] (s, m, m, rad, m/s); x,y alone: the body faces the path's "
        "tangent, the times come from the speed profile",
    )
    p.add_argument(
        "--follower", default="tracker", help="seed002, seed002-plain, pure_pursuit or tracker (default)"
    )
    add_robot_options(
        p,
        port_help="the simulated --robot in lockstep, standing at the path's start",
        surface_help="the floor: the simulated floor (default: the world's), the floor whose reach the plan "
        "keeps within and whose tables and wheel slip --calibration applies (also with --port)",
    )
    p.add_argument("--speed", type=float, help="speed cap, m/s (default: the robot's limit)")
    add_off_path_option(p)
    p.add_argument("--estimator", default="fused", help="estimator the follower sees (default fused)")
    p.add_argument("--rate", type=float, default=100.0, help="control rate, Hz (default 100)")
    add_wheel_loop_option(p)
    p.add_argument(
        "--no-wheel-loop",
        action=DeprecatedAlias,
        dest="open_loop",
        nargs=0,
        const=True,
        use="--open-loop",
        help=argparse.SUPPRESS,
    )
    p.add_argument(
        "--calibrate-gyro",
        action="store_true",
        help="spin in place one turn each way at two rates first (learns the gyro scale)",
    )
    p.add_argument(
        "--calibration",
        metavar="CAL.yaml",
        help="calibration file from `omnibot calibrate` (of this robot): its tables for --surface are "
        "uploaded (CAL) and its wheel slip there corrects the encoders",
    )
    _add_follow_outcome_arguments(p)


def _add_follow_outcome_arguments(p: argparse.ArgumentParser) -> None:
    """The ``omnibot follow`` options that judge and keep a run: its tolerances and its outputs."""
    from omnibot.navigation import Tolerances

    tol = Tolerances()
    p.add_argument(
        "--final-tolerance",
        type=float,
        default=tol.final,
        metavar="M",
        help=f"the run is done if it ends within M of the path's end (default {tol.final:g} m)",
    )
    p.add_argument(
        "--cross-track-tolerance",
        type=float,
        default=tol.cross_track,
        metavar="M",
        help=f"... and never strays more than M from the path (default {tol.cross_track:g} m)",
    )
    p.add_argument("--out", metavar="DIR", help="write follow_report.json, follow_plot.png, follow_truth.csv")
    p.add_argument("--truth", metavar="FILE.csv", help="write the ground truth t,x,y,theta (simulator only)")
    p.add_argument("--report", metavar="FILE.json", help="write the tracking report")
    p.add_argument("--plot", metavar="FILE.png", help="plot the path, the driven trajectory and the error")
