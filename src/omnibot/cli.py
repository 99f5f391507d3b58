"""The ``omnibot`` command line: ``main(argv=None)`` returns the exit status, so tests call it directly.

Every subcommand lives in its own function pair: ``_add_<name>(subparsers)`` declares its arguments,
the handler does the work (importing heavy modules lazily so ``omnibot --help`` stays fast). A
command whose arguments are declared in a heavy module is added with :func:`_command_in` or
:func:`_lazy`: a placeholder with its summary until the command is chosen (:class:`_Commands`), so
that no command imports another's modules (``tests/cli/test_startup.py`` checks ``--help``). The
commands that talk to a robot share one grammar (:mod:`omnibot.cliargs`) and leave the controller as
they found it (:mod:`omnibot.client.session`).

Exit status, the same for every command (docs/cli.md's command table):

* 0: the command did its job;
* 1: it ran but did not do its job (a path not followed within tolerance, a recording too short, a
  calibration worse than none, an ERROR reply, the link lost or silent);
* 2: the command could not start: bad arguments, files or protocol text, the wrong robot, unwritable
  output, a link that cannot be opened or whose controller does not answer HELLO;
* 70: a bug (an exception omnibot did not expect: one line, the traceback with ``--debug``);
* 130: interrupted by SIGINT (Ctrl-C), 143: by SIGTERM, 129: by SIGHUP (its terminal or SSH session
  closed; not under ``nohup``); the robot is stopped first.

Errors are one line on stderr (``omnibot: error: ...``); ``--debug`` adds the traceback. Any file a
command cannot read (not UTF-8 included) or write is such an error (status 2). A reader of standard
output that goes away (``omnibot robot show omni4 | head -1``) ends the command quietly with status
141, as SIGPIPE ends a Unix tool.
"""

from __future__ import annotations

import argparse
import errno
import importlib
import json
import math
import os
import re
import select
import sys
import traceback
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TypeAlias

from omnibot import __version__
from omnibot.cliargs import (
    DEFAULT_SEED,
    add_debug_option,
    add_log_option,
    add_robot_options,
    output_dir,
    seed_of,
)
from omnibot.errors import ConfigError, KinematicsError, OmnibotError, ProtocolError
from omnibot.extras import missing_extra

EXIT_OK, EXIT_FAILED, EXIT_USAGE, EXIT_BUG = 0, 1, 2, 70
EXIT_SIGINT, EXIT_SIGPIPE = 130, 141

Handler = Callable[[argparse.Namespace], int]


def parse_floats(text: str | Sequence[str], count: int, what: str) -> list[float]:
    """``"a,b,c"`` (or ``["a", "b", "c"]``, or a mix) -> floats, with an error that says what was expected."""
    joined = text if isinstance(text, str) else " ".join(text)
    parts = re.split(r"[,\s]+", joined.strip())
    try:
        values = [float(p) for p in parts]
    except ValueError:
        values = []
    if len(values) != count or not all(math.isfinite(v) for v in values):
        raise ConfigError(f"expected {count} numbers (comma- or space-separated), got {joined!r}", key=what)
    return values


_NUMBER = r"-?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?"
_NEGATIVE_NUMBERS = re.compile(rf"^-(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?(,\s*{_NUMBER})*,?$")
"""A negative number, or comma-separated numbers whose first is negative (``-0.2,0,0``, ``-1e-3``)."""


def positive(value: float, flag: str) -> float:
    """``value`` if it is a positive finite number, else a ConfigError naming ``flag``."""
    if not (math.isfinite(value) and value > 0):
        raise ConfigError(f"expected a positive number, got {value:g}", key=flag)
    return value


def accept_negative_numbers(parser: argparse.ArgumentParser) -> None:
    """Take option values such as ``-0.2,0,0`` or ``-1e-3`` as values, not as unknown options (argparse
    before 3.14 takes only ``-1`` and ``-.5``). For parsers with no option that looks like a number."""
    if hasattr(parser, "_negative_number_matcher"):
        parser._negative_number_matcher = _NEGATIVE_NUMBERS


# --------------------------------------------------------------------------- robot


def _robot_list(args: argparse.Namespace) -> int:
    from omnibot.robot import load_robot, preset_names

    for name in preset_names():
        print(f"{name:10s} {load_robot(name).summary}")
    return 0


def _robot_show(args: argparse.Namespace) -> int:
    from omnibot.robot import describe, load_robot

    print(describe(load_robot(args.robot)))
    return 0


def _robot_urdf(args: argparse.Namespace) -> int:
    from omnibot.robot import load_robot, to_urdf

    if args.out:
        from omnibot.cliargs import check_distinct

        check_distinct([("--out", args.out)], [("ROBOT", args.robot)])
    text = to_urdf(load_robot(args.robot))
    if args.out:
        try:
            Path(args.out).write_text(text, encoding="utf-8")
        except OSError as exc:
            raise ConfigError(f"cannot write {args.out}: {exc.strerror}", key="--out") from None
        print(f"wrote {args.out}", file=sys.stderr)
    else:
        sys.stdout.write(text)
    return 0


def _add_robot(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    p = sub.add_parser("robot", help="inspect robot descriptions and presets")
    rsub = p.add_subparsers(dest="robot_command", required=True, metavar="{list,show,urdf}")
    rsub.add_parser("list", help="list the bundled presets").set_defaults(handler=_robot_list)
    show = rsub.add_parser("show", help="print a readable summary of a robot")
    show.add_argument("robot", help="preset name (omni4, omni3, mecanum4) or description YAML file")
    show.set_defaults(handler=_robot_show)
    urdf = rsub.add_parser("urdf", help="write a URDF of the robot")
    urdf.add_argument("robot", help="preset name or description YAML file")
    urdf.add_argument("-o", "--out", help="output file (default: standard output)")
    urdf.set_defaults(handler=_robot_urdf)


# --------------------------------------------------------------------------- kinematics


def _kinematics(args: argparse.Namespace) -> int:
    from omnibot.robot import load_robot, rows

    robot = load_robot(args.robot)
    J = robot.inverse_rows
    names = [w.name for w in robot.wheels]
    out: dict[str, object] = {"robot": robot.name, "wheel_names": names}
    if args.wheels is not None:
        speeds = parse_floats(args.wheels, robot.n_wheels, "--wheels")
        twist, residual = (list(v) for v in rows.forward(J, speeds))
        out |= {"wheel_speeds": speeds, "twist": twist, "residual": residual}
        derived = [*twist, *residual]
    else:
        twist = parse_floats(args.twist, 3, "--twist")
        speeds = list(rows.apply(J, twist))
        rims = [v * w.radius for v, w in zip(speeds, robot.wheels, strict=True)]
        out |= {"twist": twist, "wheel_speeds": speeds, "rim_speeds": rims}
        derived = [*speeds, *rims]
    if not all(math.isfinite(v) for v in derived):
        given = "--wheels" if args.wheels is not None else "--twist"
        raise ConfigError("the result overflows (it is not a finite number): give smaller values", key=given)
    if args.json:
        print(json.dumps(out))
        return 0
    print(f"{robot.name}: twist vx={twist[0]:.4g} m/s  vy={twist[1]:.4g} m/s  w={twist[2]:.4g} rad/s")
    for name, speed, wheel in zip(names, speeds, robot.wheels, strict=True):
        print(f"  {name:12s} {speed:10.4f} rad/s   rim {speed * wheel.radius:8.4f} m/s")
    if args.wheels is not None:
        print(
            "  residual (rad/s, non-zero = wheels disagree, slip): " + ", ".join(f"{v:.4f}" for v in residual)
        )
    return 0


def _add_kinematics(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    p = sub.add_parser(
        "kinematics",
        help="wheel speeds for a body twist (or the twist for wheel speeds)",
        description="Inverse kinematics by default; --wheels gives forward kinematics instead. Numbers are "
        "comma- or space-separated, negative ones too: --twist -0.2 0 0, --twist -0.2,0,0",
    )
    accept_negative_numbers(p)
    p.add_argument("--robot", default="omni4", help="preset name or description file (default omni4)")
    group = p.add_mutually_exclusive_group()
    group.add_argument(
        "--twist", nargs="+", default="0,0,0", metavar="V", help="VX VY W in m/s, m/s, rad/s (body frame)"
    )
    group.add_argument(
        "--wheels", nargs="+", metavar="W", help="wheel speeds in rad/s, in the preset's wheel order"
    )
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(handler=_kinematics)


# --------------------------------------------------------------------------- sim


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


def _add_sim(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
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


# --------------------------------------------------------------------------- tour


def _tour(args: argparse.Namespace) -> int:
    from omnibot.demos import DIRECTIONS, format_table, plot_tour, run_tour
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
        png = out / f"directions_{robot.name}.png"
        try:
            plot_tour(robot, runs, png)
        except OSError as exc:
            raise ConfigError(f"cannot write {png}: {exc.strerror or exc}", key="--out") from None
        print(f"  plot: {png}\n")
    return 0


def _add_tour(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
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


# --------------------------------------------------------------------------- send, console


def _send(args: argparse.Namespace) -> int:
    from omnibot.apps.console import run_send

    positive(args.timeout, "--timeout")
    positive(args.idle_timeout, "--idle-timeout")
    return run_send(args)


def _add_send(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    p = sub.add_parser(
        "send",
        help="send protocol commands, print the replies and events",
        description="Sends each command (text protocol, several per argument with ';') and prints the "
        "replies and events. Exit status 0 if every reply is OK, 1 if any is an ERROR or the link "
        "fails, 2 for bad input. Motion sent is left running when send ends normally (STOP on an "
        "error or interrupt); the protocol goes back to text. Options may go anywhere among the "
        "commands (send STATUS --port URL 'MOVE,2,40,0,0'); the commands are sent in the order given.",
    )
    p.add_argument(
        "commands", nargs="+", metavar="COMMANDS", help="protocol text, e.g. 'MOVE,2,40,0,0;STATUS'"
    )
    add_robot_options(p)
    p.add_argument("--timeout", type=float, default=2.0, help="seconds to wait for each reply (default 2)")
    p.add_argument("--wait-idle", action="store_true", help="after the replies, wait for IDLE")
    p.add_argument("--idle-timeout", type=float, default=60.0, help="seconds --wait-idle waits (default 60)")
    p.add_argument("--binary", action="store_true", help="speak the binary protocol (MODE bit 2)")
    p.set_defaults(handler=_send, intermixed="commands")


def _console(args: argparse.Namespace) -> int:
    from omnibot.apps.console import run_console

    positive(args.timeout, "--timeout")
    return run_console(args)


def _add_console(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    p = sub.add_parser(
        "console",
        help="interactive terminal for the controller protocol",
        description="Type protocol commands; replies and decoded events are printed as they come. "
        ":help lists the console's own commands. Leaving (:quit, Ctrl-D, Ctrl-C) stops the robot and "
        "puts the MODE found at the start back.",
    )
    add_robot_options(p)
    p.add_argument("--timeout", type=float, default=2.0, help="seconds to wait for each reply (default 2)")
    p.set_defaults(handler=_console)


# --------------------------------------------------------------------------- demo


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


def _add_demo(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
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


# --------------------------------------------------------------------------- teleop ... follow

Adder: TypeAlias = "Callable[[argparse._SubParsersAction[argparse.ArgumentParser]], None]"


def _command_in(
    module: str, name: str, *, add: str = "add_arguments", run: str = "run", summary: str, description: str
) -> Adder:
    """The adder of the subcommand ``name`` (``summary``: its line in ``omnibot --help``) whose options
    (``module.add(p)``) and handler (``module.run(args)``) live in ``module``: imported only when the
    command is chosen (:class:`_Commands`) and when it runs, so the heavy imports stay in the handler."""

    def handler(args: argparse.Namespace) -> int:
        status: int = getattr(importlib.import_module(module), run)(args)
        return status

    def adder(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
        p = sub.add_parser(name, help=summary, description=description)
        getattr(importlib.import_module(module), add)(p)
        p.set_defaults(handler=handler)

    return _lazy(name, summary, adder)


def _lazy(name: str, summary: str, adder: Adder) -> Adder:
    """``adder`` declared to :class:`_Commands` by its name and summary alone: it runs (importing the
    module that declares the command's options) only when the command is chosen."""

    def register(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
        if isinstance(sub, _Commands):
            sub.add_lazy(name, summary, adder)
        else:
            adder(sub)

    return register


class _Commands(argparse._SubParsersAction):  # type: ignore[type-arg]
    """``omnibot``'s subcommands. A command added with :meth:`add_lazy` is a placeholder carrying its
    name and summary (all ``omnibot --help`` shows) until it is chosen: only then is its adder run, and
    the module that declares its options imported. So ``omnibot --help`` and ``omnibot robot list``
    import none of what the other commands need (numpy, numba, pydantic, the client, ...)."""

    def __init__(self, *args: object, **kwargs: object) -> None:
        super().__init__(*args, **kwargs)  # type: ignore[arg-type]
        self._adders: dict[str, Adder] = {}

    def add_lazy(self, name: str, summary: str, adder: Adder) -> None:
        self.add_parser(name, help=summary)
        self._adders[name] = adder

    def fill(self, name: str) -> None:
        """Run the adder of command ``name`` if it is still a placeholder (its line in the help keeps
        its place)."""
        adder = self._adders.pop(name, None)
        if adder is None:
            return
        del self._name_parser_map[name]
        place = next(k for k, a in enumerate(self._choices_actions) if a.dest == name)
        placeholder = self._choices_actions.pop(place)
        adder(self)
        filled = self._choices_actions.pop()
        if filled.help != placeholder.help:
            raise AssertionError(f"omnibot {name}: summary {placeholder.help!r} != {filled.help!r}")
        self._choices_actions.insert(place, filled)
        _add_debug_to(self._name_parser_map[name])

    def fill_all(self) -> None:
        for name in list(self._adders):
            self.fill(name)

    def __call__(
        self,
        parser: argparse.ArgumentParser,
        namespace: argparse.Namespace,
        values: str | Sequence[object] | None,
        option_string: str | None = None,
    ) -> None:
        if isinstance(values, Sequence) and values and isinstance(values[0], str):
            self.fill(values[0])
        super().__call__(parser, namespace, values, option_string)


_add_teleop = _command_in(
    "omnibot.apps.teleop",
    "teleop",
    summary="drive the robot from a joystick (pygame) or the keyboard, with a deadman",
    description="Sends VEL with its watchdog at autorepeat_rate; letting go of the enable button, "
    "losing the pad or going quiet stops the robot. On sim:// simulated time follows the wall clock.",
)
_add_dashboard = _command_in(
    "omnibot.apps.dashboard",
    "dashboard",
    summary="a web page showing the robot live (map, trail, sonars, charts) and driving it",
    description="Serves the dashboard over HTTP and a websocket; bound to 127.0.0.1 unless --host "
    "says otherwise, and then an access token is required.",
)
_add_run = _command_in(
    "omnibot.apps.run",
    "run",
    summary="several front ends on one runtime: --teleop pad|keyboard, --dashboard, --follow PATH",
    description="One runtime owns the robot; each front end is a source (pad/keyboard 200, the page 100, "
    "the follower 10) arbitrated as twist_mux does; the dashboard's emergency stop overrides all.",
)
_add_ros2 = _command_in(
    "omnibot.apps.ros2",
    "ros2",
    summary="robots on ROS 2 (DDS, no ROS install): cmd_vel, path, initialpose in; odom, tf, imu, ranges, "
    "joint_states, battery out",
    description="cmd_vel and path sources, an odometry reset and publishing sinks of one runtime per "
    "robot, on cyclonedds with ROS 2's conventions (pip install 'omnibot[ros2]'). ROS_DOMAIN_ID and "
    "ROS_AUTOMATIC_DISCOVERY_RANGE apply.",
)
_add_record = _command_in(
    "omnibot.apps.teach",
    "record",
    add="add_record_arguments",
    run="run_record",
    summary="teach a path: record the robot's odometry while it is pushed by hand or driven",
    description="Samples the robot's own pose estimate (encoders, tracking wheels, gyro) by distance or "
    "time into a path file t,x,y,theta[,v]. In the simulator a hand pushes the robot along a shape with "
    "the motors off (seed 002's teaching), or VEL commands drive it; with --port it listens.",
)
_add_follow = _command_in(
    "omnibot.apps.teach",
    "follow",
    add="add_follow_arguments",
    run="run_follow",
    summary="repeat a path: a path follower drives it, with a report and a plot",
    description="Runs a path follower at 100 Hz on the host (VEL out, TEL in); by default on the simulated "
    "robot in lockstep, measured against its ground truth. Exit status 1 if the run was not completed "
    "(the follower did not finish, or the run was outside --final-tolerance/--cross-track-tolerance).",
)
_add_map = _command_in(
    "omnibot.apps.mapping",
    "map",
    summary="map a room with the robot's scanner (SLAM) while a path or a person drives it",
    description="Drives the robot along --path (or by --teleop) with the wheel-speed loop closed while the "
    "SLAM (scan matching and a pose graph with loop closures) corrects the odometry; writes the map "
    "(map_server's YAML + PGM), the trajectories (TUM) and, on the simulator, a report scored against "
    "the truth. Exit status 1 if no map was made or the path was not completed.",
)
_add_goto = _command_in(
    "omnibot.apps.goto",
    "goto",
    summary="go to a place on a saved map: localise with the scanner, plan, follow, avoid what the map lacks",
    description="Loads the map (map_server's YAML + image), localises the robot in it (particle filter "
    "and scan-to-map matching), plans on the map inflated by the robot's radius and follows the plan, "
    "stopping and re-planning for obstacles the map does not have. Exit status 0 when it arrived within "
    "the tolerances, 1 when not (the reason is printed), 2 for a bad map or goal.",
)


# --------------------------------------------------------------------------- calibrate


def _add_calibrate_now(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    importlib.import_module("omnibot.apps.calibrate").add_parser(sub)


_add_calibrate = _lazy(
    "calibrate",
    "seed 000's power calibration (K, K_l, K_t, K_r), gyro and odometry geometry, with a report",
    _add_calibrate_now,
)


# --------------------------------------------------------------------------- parser


def _add_log_now(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    importlib.import_module("omnibot.apps.log").add_log_command(sub)


_add_log = _lazy("log", "inspect, plot, export and replay a run recorded with --log FILE.mcap", _add_log_now)


def build_parser(*, full: bool = False) -> argparse.ArgumentParser:
    """The ``omnibot`` argument parser: one subcommand per entry of ``ADDERS``. The commands whose
    options live in heavy modules are declared when chosen (:class:`_Commands`); ``full`` declares
    them all now."""
    parser = argparse.ArgumentParser(
        prog="omnibot", description="Drive omnidirectional mobile robots, real or simulated."
    )
    parser.add_argument("--version", action="version", version=f"omnibot {__version__}")
    parser.add_argument("--debug", action="store_true", help="show the traceback of an error")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND", action=_Commands)
    for add in ADDERS:
        add(sub)
    for p in sub.choices.values():
        _add_debug_to(p)
    if full:
        assert isinstance(sub, _Commands)
        sub.fill_all()
    return parser


def _add_debug_to(p: argparse.ArgumentParser) -> None:
    """``--debug`` on a (sub)command and its own subcommands, so that it can go anywhere on the line."""
    if "--debug" not in p._option_string_actions:
        add_debug_option(p)
    for action in p._actions:
        if isinstance(action, argparse._SubParsersAction):
            for child in action.choices.values():
                _add_debug_to(child)


ADDERS: list[Adder] = [
    _add_robot,
    _add_kinematics,
    _add_sim,
    _add_tour,
    _add_send,
    _add_console,
    _add_demo,
    _add_record,
    _add_follow,
    _add_teleop,
    _add_dashboard,
    _add_run,
    _add_ros2,
    _add_map,
    _add_goto,
    _add_calibrate,
    _add_log,
]


def exit_status(exc: BaseException) -> int:
    """The exit status of a command that ended with ``exc`` (see the module docstring)."""
    from omnibot.signals import Terminated

    if isinstance(exc, Terminated):
        return 128 + exc.signum
    if isinstance(exc, KeyboardInterrupt):
        return EXIT_SIGINT
    if isinstance(exc, ConfigError | KinematicsError | ProtocolError | UnicodeDecodeError):
        return EXIT_USAGE
    if missing_extra(exc) is not None:
        return EXIT_USAGE  # a part of omnibot that is not installed (pip install 'omnibot[...]')
    if isinstance(exc, OSError) and (exc.filename is not None or _output_full(exc)):
        return EXIT_USAGE  # a file it cannot read or write, or no room for its output
    if isinstance(exc, OmnibotError):
        return EXIT_FAILED
    return EXIT_BUG


def main(argv: Sequence[str] | None = None) -> int:
    """Run the ``omnibot`` command line; returns the exit status."""
    from omnibot.apps.recording import command_recording
    from omnibot.signals import Terminated, terminate_cleanly

    parser = build_parser()
    command = _command(sys.argv[1:] if argv is None else argv)
    try:
        args, extra = parser.parse_known_args(argv)  # a chosen command's module is imported here
    except ModuleNotFoundError as exc:
        if (line := missing_extra(exc, command)) is None:
            raise
        print(f"omnibot: error: {line}", file=sys.stderr)
        return EXIT_USAGE
    intermixed = getattr(args, "intermixed", None)
    if extra and intermixed and not any(e.startswith("-") for e in extra):
        # `send CMD --port URL CMD2`: options anywhere, the commands kept in the order given
        getattr(args, intermixed).extend(extra)
    elif extra:
        parser.error(f"unrecognized arguments: {' '.join(extra)}")
    handler: Handler = args.handler
    if sys.stdout is None:  # started with its standard output closed (`>&-`): what it says would be lost
        print(
            "omnibot: error: standard output is closed; give it a file (>/dev/null to discard)",
            file=sys.stderr,
        )
        return EXIT_USAGE
    try:
        with terminate_cleanly(), command_recording(args) as rec:
            args.recording = rec  # handed by the command to the sessions it opens and its runtimes
            status = handler(args)
            sys.stdout.flush()  # a reader that went away shows up here, not at interpreter exit
        if rec is not None and rec.failure is not None and status == EXIT_OK:
            # the robot did its job, the --log it was asked for is incomplete (warned when it failed)
            return EXIT_FAILED
        return status
    except (Exception, KeyboardInterrupt) as exc:
        if isinstance(exc, BrokenPipeError) and _stdout_gone():
            # `omnibot ... | head -1`: stop quietly, as a Unix tool killed by SIGPIPE, and send what is
            # still buffered to /dev/null so that Python's flush at exit does not complain (Python's
            # docs, "Note on SIGPIPE" in the signal module)
            _silence_stdout()
            return EXIT_SIGPIPE
        status = exit_status(exc)
        if args.debug:
            traceback.print_exc()
        if isinstance(exc, KeyboardInterrupt):
            signal_name = exc.signum.name if isinstance(exc, Terminated) else "SIGINT"
            print(f"omnibot: interrupted ({signal_name})", file=sys.stderr)
        elif status == EXIT_BUG:
            print(
                f"omnibot: internal error: {type(exc).__name__}: {exc} (run with --debug for the traceback)",
                file=sys.stderr,
            )
        else:
            print(f"omnibot: error: {_message(exc, command)}", file=sys.stderr)
        if _output_full(exc):
            _silence_stdout()  # what standard output still holds goes to /dev/null: no second failure
        return status


def _command(argv: Sequence[str]) -> str | None:
    """The command of an ``omnibot`` command line (its first word that is not an option: the
    top-level options take no value)."""
    return next((word for word in argv if not word.startswith("-")), None)


def _message(exc: BaseException, command: str | None = None) -> str:
    """The one line an error of ``command`` is told in."""
    if (line := missing_extra(exc, command)) is not None:
        return line
    if isinstance(exc, UnicodeDecodeError):  # text where the reader checked for none (it names no file)
        return f"not UTF-8 text: {exc}"
    if isinstance(exc, OSError) and exc.filename is not None:
        return f"{exc.filename}: {exc.strerror or exc}"
    if _output_full(exc):
        assert isinstance(exc, OSError)
        return f"cannot write the output: {exc.strerror}"
    return str(exc)


_FULL = (errno.ENOSPC, errno.EDQUOT, errno.EFBIG)
"""Errors of a write that found no room."""


def _output_full(exc: BaseException) -> bool:
    """A write to standard output that found no room (a full disk, /dev/full)."""
    return isinstance(exc, OSError) and exc.filename is None and exc.errno in _FULL


def _silence_stdout() -> None:
    """Point standard output's file descriptor at /dev/null (what it still buffers goes there)."""
    try:
        fd = sys.stdout.fileno()
    except (AttributeError, OSError, ValueError):
        return
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, fd)
    os.close(devnull)


def _stdout_gone() -> bool:
    """Whether nobody reads standard output any more (the write end of a pipe whose reader closed)."""
    try:
        fd = sys.stdout.fileno()
    except (AttributeError, OSError, ValueError):
        return False
    poller = select.poll()
    poller.register(fd, select.POLLOUT)
    return any(ev & select.POLLERR for _, ev in poller.poll(0))


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
