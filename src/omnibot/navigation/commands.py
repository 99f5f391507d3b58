"""``omnibot record`` and ``omnibot follow``: teach and repeat from the command line.

Both default to the simulated robot in lockstep (faster than real time, deterministic for a seed);
``--port URL`` drives any link instead (a real board, ``sim://...``, ``tcp://...``). Errors in the
input (a malformed path file, an unknown follower, bad numbers) are OmnibotErrors, which the CLI
prints as one line with exit status 2.
"""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path as FsPath
from typing import Any

from omnibot.errors import ConfigError


def _positive(value: float, flag: str) -> float:
    if not (math.isfinite(value) and value > 0):
        raise ConfigError(f"expected a positive number, got {value:g}", key=flag)
    return value


def _robot(name: str) -> Any:
    from omnibot.robot.description import load_robot

    return load_robot(name)


def _open_port(port: str, robot: Any) -> Any:
    from omnibot.client.client import RobotClient

    return RobotClient.open(port, robot)


def run_follow(args: argparse.Namespace) -> int:
    from omnibot.control.followers.base import follower_names
    from omnibot.control.paths.files import read_path
    from omnibot.estimation.estimator import ESTIMATORS
    from omnibot.estimation.odometry import Pose2D
    from omnibot.navigation.session import FollowOptions, follow_path, simulated_client, summary
    from omnibot.progress import progress_bar

    path = read_path(args.path)
    robot = _robot(args.robot)
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
    rate = _positive(args.rate, "--rate")
    speed = _positive(args.speed, "--speed") if args.speed is not None else None
    options = FollowOptions(
        follower=args.follower,
        speed=speed,
        estimator=args.estimator,
        rate=rate,
        wheel_loop=not args.no_wheel_loop,
        calibrate_gyro=args.calibrate_gyro,
        slip=_slip(args),
    )
    surface = args.surface or "wood"
    if args.port:
        client = _open_port(args.port, robot)
    else:
        client = simulated_client(robot, surface=surface, seed=args.seed, start=Pose2D(*path.start))
    metres = "{l_bar}{bar}| {n:.2f}/{total:.2f} m [{elapsed}<{remaining}]"
    with client, progress_bar(f"follow {FsPath(args.path).name}", path.length, bar_format=metres) as bar:
        options.progress = bar
        run, report, _ = follow_path(client, robot, path, options)
    report["path_file"] = str(args.path)
    report["link"] = args.port or f"sim://{robot.name} (lockstep, surface {surface}, seed {args.seed})"
    if options.slip is not None:
        report["slip_calibration"] = {"file": str(args.calibration), **options.slip.as_dict()}
    print(f"omnibot follow: {robot.name}, {args.follower}, {len(path)} points, {path.length:.2f} m")
    print(f"  {summary(report)}")
    if args.truth:
        if not run.has_truth:
            raise ConfigError("no ground truth on this link (only the simulator has one)", key="--truth")
        _write_truth(run, FsPath(args.truth))
        print(f"  truth: {args.truth}")
    if args.report:
        _write(FsPath(args.report), json.dumps(report, indent=2) + "\n", "--report")
        print(f"  report: {args.report}")
    if args.plot:
        from omnibot.navigation.plot import plot_run

        try:
            plot_run(run, args.plot, title=f"{robot.name}: {args.follower} on {FsPath(args.path).name}")
        except OSError as exc:
            raise ConfigError(f"cannot write {args.plot}: {exc.strerror or exc}", key="--plot") from None
        print(f"  plot: {args.plot}")
    return 0 if report["completed"] else 1


def _slip(args: argparse.Namespace) -> Any:
    """The floor's wheel-slip coefficients from ``--calibration`` (None without one)."""
    if not args.calibration:
        return None
    from omnibot.calibration.calfile import load_calibration

    cal = load_calibration(args.calibration)
    try:
        return cal.slip_for(args.surface)
    except ConfigError as exc:
        raise ConfigError(f"{args.calibration}: {exc}", key="--surface") from None


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
    from omnibot.control.paths.files import write_path
    from omnibot.control.paths.standard import standard_path
    from omnibot.control.paths.teach import PathRecorder
    from omnibot.navigation.record import teach
    from omnibot.navigation.session import simulated_client

    robot = _robot(args.robot)
    mode = args.teach or ("listen" if args.port else "push")
    every = args.sample_time if args.sample_time is not None else args.sample_distance
    _positive(every, "--sample-time" if args.sample_time is not None else "--sample-distance")
    speed = _positive(args.speed, "--speed")
    duration = _positive(args.duration, "--duration")
    recorder = PathRecorder(
        "time" if args.sample_time is not None else "distance",
        every,
        store_heading=not args.fixed_heading,
        store_speed=args.store_speed,
    )
    shape = (
        standard_path(args.shape, size=_positive(args.size, "--size"), heading=args.heading)
        if mode != "listen"
        else None
    )
    out = FsPath(args.out)
    if args.port:
        client = _open_port(args.port, robot)
    else:
        client = simulated_client(robot, surface=args.surface, seed=args.seed)
    with client:
        result = teach(client, robot, recorder, mode=mode, shape=shape, speed=speed, duration=duration)
    try:
        write_path(result.path, out)
    except OSError as exc:
        raise ConfigError(f"cannot write {out}: {exc}", key="--out") from None
    what = {
        "push": f"pushed by hand along {args.shape}",
        "drive": f"driven along {args.shape}",
        "listen": "recorded",
    }
    print(
        f"omnibot record: {robot.name} {what[mode]}: {len(result.path)} points, {result.path.length:.2f} m "
        f"in {result.duration:.1f} s -> {out}"
    )
    if result.truth_error is not None:
        print(f"  recorded end is {100 * result.truth_error:.2f} cm from the true end (odometry drift)")
    return 0


def add_follow_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("path", help="path file: CSV t,x,y,theta[,v] (s, m, m, rad, m/s)")
    p.add_argument(
        "--follower", default="tracker", help="seed002, seed002-plain, pure_pursuit or tracker (default)"
    )
    p.add_argument("--robot", default="omni4", help="preset name or description file (default omni4)")
    p.add_argument(
        "--port", help="link URL (default: the simulated robot in lockstep, standing at the path's start)"
    )
    p.add_argument("--speed", type=float, help="speed cap, m/s (default: the robot's limit)")
    p.add_argument("--estimator", default="fused", help="estimator the follower sees (default fused)")
    p.add_argument("--rate", type=float, default=100.0, help="control rate, Hz (default 100)")
    p.add_argument("--no-wheel-loop", action="store_true", help="leave the controller's wheel-speed loop off")
    p.add_argument(
        "--calibrate-gyro",
        action="store_true",
        help="spin in place one turn each way first (learns the gyro scale)",
    )
    p.add_argument(
        "--calibration",
        metavar="CAL.yaml",
        help="calibration file from `omnibot calibrate`: its wheel slip for --surface corrects the encoders",
    )
    p.add_argument(
        "--surface",
        help="the floor: simulated floor (wood by default; carpet, concrete, linoleum) and the floor "
        "whose slip --calibration applies",
    )
    p.add_argument("--seed", type=int, default=1, help="simulator seed (default 1)")
    p.add_argument("--truth", metavar="FILE.csv", help="write the ground truth t,x,y,theta (simulator only)")
    p.add_argument("--report", metavar="FILE.json", help="write the tracking report")
    p.add_argument("--plot", metavar="FILE.png", help="plot the path, the driven trajectory and the error")


def add_record_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--out", required=True, metavar="PATH.csv", help="path file to write")
    p.add_argument("--port", help="link URL (default: the simulated robot in lockstep)")
    p.add_argument("--robot", default="omni4", help="preset name or description file (default omni4)")
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
        "--heading", choices=("fixed", "tangent"), default="fixed", help="shape heading (default fixed)"
    )
    p.add_argument("--speed", type=float, default=0.3, help="speed of the push or drive, m/s (default 0.3)")
    sampling = p.add_mutually_exclusive_group()
    sampling.add_argument(
        "--sample-distance", type=float, default=0.02, help="keep a pose every D m (default 0.02)"
    )
    sampling.add_argument("--sample-time", type=float, help="keep a pose every T s instead")
    p.add_argument("--store-speed", action="store_true", help="add the v column (speed while taught)")
    p.add_argument("--fixed-heading", action="store_true", help="store the start heading on every row")
    p.add_argument("--duration", type=float, default=30.0, help="listen: seconds to record (default 30)")
    p.add_argument("--surface", default="wood", help="simulated floor (default wood)")
    p.add_argument("--seed", type=int, default=1, help="simulator seed (default 1)")
