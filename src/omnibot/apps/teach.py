"""``omnibot record`` and ``omnibot follow``: teach and repeat from the command line.

Both default to the simulated robot in lockstep (faster than real time, deterministic for a seed);
``--port URL`` drives any link instead (a real board, ``sim://...``, ``tcp://...``), the robot being
the one the controller names (:func:`omnibot.client.session.robot_on_link`). Either way the session
leaves the controller stopped and in the MODE it was found in (:mod:`omnibot.client.session`).
Errors in the input (a malformed path file, an unknown follower, bad numbers) are ConfigErrors: one
line, exit status 2. A run that did not do its job exits 1 with the reason: a recording shorter than
:data:`~omnibot.navigation.outcome.MIN_POINTS` points or :data:`~omnibot.navigation.outcome.MIN_LENGTH`
m, a follow run outside its tolerances (:class:`~omnibot.navigation.outcome.Tolerances`).
"""

from __future__ import annotations

import argparse
import contextlib
import json
import math
from collections.abc import Iterator
from pathlib import Path as FsPath
from typing import TYPE_CHECKING, Any

from omnibot.cliargs import (
    DeprecatedAlias,
    add_robot_options,
    add_wheel_loop_option,
    check_distinct,
    check_plot,
    check_sim_options,
    recording_of,
    seed_of,
    sim_robot,
    use_calibration,
    world_of,
)
from omnibot.errors import ConfigError
from omnibot.outputs import check_writable

if TYPE_CHECKING:
    from omnibot.control import Path, PathRecorder
    from omnibot.navigation import Tolerances


def _positive(value: float, flag: str) -> float:
    if not (math.isfinite(value) and value > 0):
        raise ConfigError(f"expected a positive number, got {value:g}", key=flag)
    return value


@contextlib.contextmanager
def _robot_client(args: argparse.Namespace, start: Any = None) -> Iterator[tuple[Any, Any]]:
    """(client, robot): ``--port``'s robot (checked against ``--robot``), or the simulated ``--robot``
    in ``--world``: standing at the world's own start where it has one (``room``, ``corridor``), else
    at ``start`` (``follow``: the path's start), else at the origin; the controller is left as it was
    found on every way out."""
    from omnibot.client import guarded, robot_session
    from omnibot.navigation import simulated_client
    from omnibot.robot import load_robot

    recording = recording_of(args)
    if args.port:
        with robot_session(args.port, args.robot, recording=recording) as session:
            yield session.client, session.robot
        return
    from omnibot.cliargs import check_world
    from omnibot.sim import load_world

    check_world(args)
    robot = load_robot(sim_robot(args))
    world = world_of(args)
    if load_world(world).start is not None:
        start = None  # the world's start: a path is followed in its own frame from where the robot stands
    client = simulated_client(
        robot,
        surface=args.surface,
        seed=seed_of(args),
        start=start,
        world=None if world == "empty" else world,
    )
    with guarded(client, robot=robot, recording=recording):
        yield client, robot


def run_follow(args: argparse.Namespace) -> int:
    """Run ``omnibot follow``: follow a path file and report tracking; the exit status (1 when the run
    did not complete, its failures printed)."""
    from omnibot.control import read_path
    from omnibot.motion import Pose2D
    from omnibot.navigation import FollowOptions, follow_path, summary, verdict
    from omnibot.progress import progress_bar

    check_sim_options(args, allowed=("surface",))
    path = read_path(args.path)
    _check_follower_and_estimator(args)
    rate = _positive(args.rate, "--rate")
    speed = _positive(args.speed, "--speed") if args.speed is not None else None
    tolerances = _tolerances(args)
    targets = _follow_targets(args)
    metres = "{l_bar}{bar}| {n:.2f}/{total:.2f} m [{elapsed}<{remaining}]"
    with (
        _robot_client(args, start=Pose2D(*path.start)) as (client, robot),
        progress_bar(f"follow {FsPath(args.path).name}", path.length, bar_format=metres) as bar,
    ):
        floor = use_calibration(args, client, robot)  # the floor's tables and creep, uploaded
        slip = floor.params if floor is not None else None
        options = FollowOptions(
            follower=args.follower,
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
        final=_positive(args.final_tolerance, "--final-tolerance"),
        cross_track=_positive(args.cross_track_tolerance, "--cross-track-tolerance"),
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
    if not args.out:
        return None
    out = FsPath(args.out)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ConfigError(f"cannot make directory {out}: {exc.strerror or exc}", key="--out") from None
    return out


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


def run_record(args: argparse.Namespace) -> int:
    """Run ``omnibot record``: record a taught or standard path to ``--path``; the exit status (1 when
    the recording is no path to follow, and nothing is written)."""
    from omnibot.control import write_path
    from omnibot.navigation import check_recording, teach

    check_sim_options(args)
    if not args.path:
        raise ConfigError("say where to write the path: --path FILE.csv", key="--path")
    mode = args.teach or ("listen" if args.port else "push")
    recorder, speed, duration, shape = _teaching(args, mode)
    out = FsPath(args.path)
    check_writable(out, "--path")
    check_distinct([("--path", out), ("--log", args.log)])
    with _robot_client(args) as (client, robot):
        result = teach(
            client,
            robot,
            recorder,
            mode=mode,
            shape=shape,
            speed=speed,
            duration=duration,
            recording=recording_of(args),
        )
    problem = check_recording(result)
    for text in result.warnings:
        print(f"omnibot record: warning: {text}")
    what = {
        "push": f"pushed by hand along {args.shape}",
        "drive": f"driven along {args.shape}",
        "listen": "recorded",
    }
    if problem is not None:
        print(f"omnibot record: {robot.name} {what[mode]}: {problem}; nothing written")
        return 1
    assert result.path is not None  # check_recording saw to it
    try:
        write_path(result.path, out)
    except OSError as exc:
        raise ConfigError(f"cannot write {out}: {exc.strerror or exc}", key="--path") from None
    print(
        f"omnibot record: {robot.name} {what[mode]}: {len(result.path)} points, {result.path.length:.2f} m "
        f"in {result.duration:.1f} s -> {out}"
    )
    if result.truth_error is not None:
        print(f"  recorded end is {100 * result.truth_error:.2f} cm from the true end (odometry drift)")
    return 0


def _teaching(args: argparse.Namespace, mode: str) -> tuple[PathRecorder, float, float, Path | None]:
    """How ``omnibot record`` teaches: the recorder (sampling every ``--sample-time`` s or
    ``--sample-distance`` m, storing the heading unless it is fixed), the speed, the duration and,
    unless it listens to another driver, the standard shape driven or pushed along."""
    from omnibot.control import PathRecorder, standard_path

    every = args.sample_time if args.sample_time is not None else args.sample_distance
    _positive(every, "--sample-time" if args.sample_time is not None else "--sample-distance")
    speed = _positive(args.speed, "--speed")
    duration = _positive(args.duration, "--duration")
    heading = args.heading or "measured"
    recorder = PathRecorder(
        "time" if args.sample_time is not None else "distance",
        every,
        store_heading=heading != "fixed",
        store_speed=args.store_speed,
    )
    shape = (
        standard_path(
            args.shape,
            size=_positive(args.size, "--size"),
            heading="tangent" if heading == "tangent" else "fixed",
        )
        if mode != "listen"
        else None
    )
    return recorder, speed, duration, shape


def add_follow_arguments(p: argparse.ArgumentParser) -> None:
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


def add_record_arguments(p: argparse.ArgumentParser) -> None:
    """The ``omnibot record`` options: the file to write, robot or port, and how the path is taught."""
    from omnibot.navigation import MIN_LENGTH, MIN_POINTS

    p.add_argument("--path", metavar="FILE.csv", help="path file to write (required)")
    p.add_argument("--out", action=DeprecatedAlias, dest="path", use="--path", help=argparse.SUPPRESS)
    add_robot_options(p)
    p.add_argument(
        "--teach",
        choices=("push", "drive", "listen"),
        help="push: a simulated hand pushes the robot, motors off (default in the simulator); drive: by "
        "VEL commands along --shape; listen: record while someone else moves it (default with --port)",
    )
    p.add_argument(
        "--shape", default="s_curve", help="standard path to push or drive along (default s_curve)"
    )
    p.add_argument("--size", type=float, default=1.0, help="shape size, m (default 1)")
    p.add_argument(
        "--heading",
        choices=("measured", "fixed", "tangent"),
        help="measured (default): the shape is moved along at a fixed heading and the file keeps the "
        "heading odometry measured; fixed: the start heading on every row; tangent: the shape is moved "
        "along facing its tangent",
    )
    p.add_argument(
        "--fixed-heading",
        action=DeprecatedAlias,
        dest="heading",
        nargs=0,
        const="fixed",
        use="--heading fixed",
        help=argparse.SUPPRESS,
    )
    p.add_argument("--speed", type=float, default=0.3, help="speed of the push or drive, m/s (default 0.3)")
    sampling = p.add_mutually_exclusive_group()
    sampling.add_argument(
        "--sample-distance", type=float, default=0.02, help="keep a pose every D m (default 0.02)"
    )
    sampling.add_argument("--sample-time", type=float, help="keep a pose every T s instead")
    p.add_argument("--store-speed", action="store_true", help="add the v column (speed while taught)")
    p.add_argument("--duration", type=float, default=30.0, help="listen: seconds to record (default 30)")
    p.epilog = (
        f"A recording of fewer than {MIN_POINTS} points or shorter than {MIN_LENGTH:g} m is not written "
        "(exit status 1)."
    )
