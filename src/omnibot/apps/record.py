"""``omnibot record``: teach a path, the robot pushed by hand (the simulator's), driven along a standard
shape or listened to while someone else moves it, written to ``--path``; exit status 1 when the
recording is no path to follow (shorter than :data:`~omnibot.navigation.record.MIN_POINTS` points or
:data:`~omnibot.navigation.record.MIN_LENGTH` m), and nothing is written. The robot it drives:
:func:`omnibot.apps.teach.robot_client`.
"""

from __future__ import annotations

import argparse
from pathlib import Path as FsPath
from typing import TYPE_CHECKING

from omnibot.apps.teach import robot_client
from omnibot.cliargs import (
    DeprecatedAlias,
    add_robot_options,
    check_distinct,
    check_sim_options,
    positive,
    recording_of,
)
from omnibot.errors import ConfigError
from omnibot.outputs import check_writable

if TYPE_CHECKING:
    from omnibot.control import Path, PathRecorder


def run(args: argparse.Namespace) -> int:
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
    with robot_client(args) as (client, robot):
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
        "listen": "listened to",
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
    positive(every, "--sample-time" if args.sample_time is not None else "--sample-distance")
    speed = positive(args.speed, "--speed")
    duration = positive(args.duration, "--duration")
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
            size=positive(args.size, "--size"),
            heading="tangent" if heading == "tangent" else "fixed",
        )
        if mode != "listen"
        else None
    )
    return recorder, speed, duration, shape


def add_arguments(p: argparse.ArgumentParser) -> None:
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
