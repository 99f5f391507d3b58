"""``omnibot demo`` (the main job: seed 000's motion examples through the whole stack) and ``omnibot
tour`` (seed 003's main directions in the simulator, open loop, with plots).

Light to import: the handlers import the demos.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import TYPE_CHECKING

from omnibot.cliargs import DEFAULT_SEED, add_robot_options, output_dir, positive, seed_of
from omnibot.errors import ConfigError

if TYPE_CHECKING:
    from omnibot.demos import DirectionRun
    from omnibot.robot import RobotDescription

EXIT_OK, EXIT_FAILED = 0, 1


def _demo(args: argparse.Namespace) -> int:
    from omnibot.cliargs import check_sim_options, check_world, recording_of, world_of
    from omnibot.demos import run_demo

    check_sim_options(args)
    if args.port is None:
        check_world(args)
    out = output_dir(args.out)
    report, ok = run_demo(
        args.port,
        args.robot,
        out,
        seed=seed_of(args),
        world=world_of(args),
        surface=args.surface,
        recording=recording_of(args),
    )
    print(report)
    return EXIT_OK if ok else EXIT_FAILED


def add_demo(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """``omnibot demo``: the robot options of every robot command, and ``--out``."""
    p = sub.add_parser(
        "demo",
        help="the main job: seed 000's motion examples through the whole stack, commanded vs achieved",
        description="Starts the simulated robot on a pty (omnibot sim --pty) and drives seed 000's examples "
        "through client -> text protocol -> pty -> firmware -> simulator; --port drives a real board instead.",
    )
    add_robot_options(p, world="room", port_help="the simulated --robot on a pty, omnibot sim --pty")
    p.add_argument(
        "--out", default="out", metavar="DIR", help="directory for the plot and truth CSV (default ./out)"
    )
    p.set_defaults(handler=_demo)


def _tour(args: argparse.Namespace) -> int:
    from omnibot.demos import DIRECTIONS, format_table, run_tour
    from omnibot.floor import get_surface
    from omnibot.progress import progress_bar
    from omnibot.robot import load_robot, preset_names

    surface = args.surface or "wood"
    get_surface(surface)
    if not 0 < args.power <= 255:
        raise ConfigError(f"expected 1..255 PWM counts, got {args.power}", key="--power")
    positive(args.duration, "--duration")
    names = preset_names() if args.robot == "all" else [args.robot]
    robots = [load_robot(name) for name in names]
    out = output_dir(args.out)
    for robot in robots:
        with progress_bar(f"tour {robot.name}", len(DIRECTIONS), unit="motion") as bar:
            runs = run_tour(
                robot,
                power=args.power,
                duration=args.duration,
                surface=surface,
                seed=seed_of(args),
                progress=bar,
            )
        print(format_table(robot, runs))
        print(_plot(robot, runs, out / f"directions_{robot.name}.png"))
    return 0


def _plot(robot: RobotDescription, runs: list[DirectionRun], png: Path) -> str:
    """Draw the tour's plot (where matplotlib is installed); the line saying where, or why not."""
    from omnibot.demos import plot_tour
    from omnibot.outputs import made_directory
    from omnibot.plots import unavailable

    why = unavailable()
    if why is not None:
        return f"  plot left out: {why}\n"
    try:
        plot_tour(robot, runs, made_directory(png.parent, "--out") / png.name)
    except OSError as exc:
        raise ConfigError(f"cannot write {png}: {exc.strerror or exc}", key="--out") from None
    return f"  plot: {png}\n"


def add_tour(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """``omnibot tour``: the robots, the floor, the power and duration of each motion, ``--out``."""
    p = sub.add_parser(
        "tour",
        help="drive each robot through seed 003's main directions in the simulator, open loop, with plots",
        description="Runs the physics alone (no controller, no link): PWM straight to the motors.",
    )
    p.add_argument(
        "--robot", default="all", metavar="PRESET|FILE|all", help="the robot, or 'all' presets (default)"
    )
    p.add_argument("--surface", metavar="NAME", help="simulated floor (default wood)")
    p.add_argument("--seed", type=int, metavar="N", help=f"simulator seed (default {DEFAULT_SEED})")
    p.add_argument("--power", type=int, default=180, help="PWM counts of the busiest motor (default 180)")
    p.add_argument("--duration", type=float, default=1.0, help="seconds per motion (default 1)")
    p.add_argument("--out", default="out", metavar="DIR", help="directory for the plots (default ./out)")
    p.set_defaults(handler=_tour)
