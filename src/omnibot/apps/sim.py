"""``omnibot sim --pty``: the simulated robot (firmware + physics) served on a pseudo-terminal, one
robot or a fleet in one world; ``--log`` records the controller's side of the link.

Light to import: the handler imports the simulator.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from omnibot.cliargs import DEFAULT_SEED, add_log_option, seed_of
from omnibot.errors import ConfigError


def _sim(args: argparse.Namespace) -> int:
    from omnibot.floor import SURFACES
    from omnibot.robot import load_robot
    from omnibot.sim import load_world, run_pty_emulator

    robots = args.robot or ["omni4"]
    if len(robots) > 1 or "?" in robots[0]:  # a fleet (of one, too: a robot's own options)
        return _sim_fleet(args, robots)
    robot = load_robot(robots[0])
    if args.surface is not None and args.surface not in SURFACES:
        raise ConfigError(
            f"unknown surface {args.surface!r}; expected one of: {', '.join(SURFACES)}", key="--surface"
        )
    if args.world is not None:
        load_world(args.world)  # a bad world is reported before the pty appears
    if not args.pty:
        raise ConfigError("only the pty emulator exists so far: add --pty", key="omnibot sim")
    if args.foxglove is not None:
        raise ConfigError(
            "sim --pty records its side with --log; --foxglove goes on the command that drives it",
            key="--foxglove",
        )
    truth = Path(args.truth) if args.truth else None
    log = Path(args.log) if args.log else None
    if log is not None:
        from omnibot.cliargs import check_distinct
        from omnibot.outputs import check_writable

        check_writable(log, "--log")
        check_distinct([("--truth", truth), ("--log", log)])
    seed = seed_of(args)
    if log is None:
        return run_pty_emulator(
            robot, seed=seed, surface=args.surface, world=args.world, truth=truth, baud=args.baud
        )
    from omnibot.logs import RecordedDevice, Recorder

    log_recorder = Recorder(log)  # the bytes both ways and the truth
    try:
        return run_pty_emulator(
            robot,
            seed=seed,
            surface=args.surface,
            world=args.world,
            truth=truth,
            baud=args.baud,
            wrap=lambda device: RecordedDevice(device, log_recorder, robot),
        )
    finally:
        log_recorder.close()


def _sim_fleet(args: argparse.Namespace, robots: list[str]) -> int:
    from omnibot.sim import parse_member, run_pty_fleet

    if not args.pty:
        raise ConfigError("only the pty emulator exists so far: add --pty", key="omnibot sim")
    for flag, given in (("--truth", args.truth), ("--log", args.log), ("--foxglove", args.foxglove)):
        if given is not None:
            raise ConfigError(f"{flag} records one robot: not with several --robot", key=flag)
    members = [parse_member(text, k, seed_of(args)) for k, text in enumerate(robots)]
    return run_pty_fleet(members, surface=args.surface, world=args.world, baud=args.baud)


def add_sim(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """``omnibot sim``: the robot (or a fleet), its world and floor, the pty's pacing, ``--log``."""
    p = sub.add_parser(
        "sim",
        help="run the simulated robot (firmware + physics) on a pseudo-terminal",
        description="Runs the firmware and the simulator as one process on a pty, in real time, "
        "pacing bytes to the baud rate. The first stdout line is the device path; a robot with a scanner "
        "gets a second pty serving an emulated RPLIDAR (a line 'scanner PATH'). Ends on SIGINT/SIGTERM/SIGHUP.",
    )
    p.add_argument("--pty", action="store_true", help="serve on a pseudo-terminal (required)")
    p.add_argument(
        "--robot",
        action="append",
        metavar="PRESET|FILE",
        help="preset name or description file (default omni4); repeat it for a fleet in one world, one "
        "pty each (a line NAME PATH per robot): PRESET?name=R&pose=X,Y,THETA&seed=N (pose in m, m, degrees)",
    )
    p.add_argument(
        "--seed",
        type=int,
        default=DEFAULT_SEED,
        help=f"random seed of the sensor noise (default {DEFAULT_SEED}; a fleet's k-th robot: seed + k)",
    )
    p.add_argument("--surface", help="floor surface: wood, carpet, concrete, linoleum (default: the world's)")
    p.add_argument(
        "--world",
        help="world name (empty, room, corridor, house, long_corridor) or world YAML file (default empty)",
    )
    p.add_argument("--truth", metavar="FILE.csv", help="write the ground-truth trajectory t,x,y,theta")
    p.add_argument("--baud", type=int, default=115200, help="pace bytes to this baud rate (default 115200)")
    add_log_option(p)
    p.set_defaults(handler=_sim)
