"""The ``omnibot`` command line: ``main(argv=None)`` returns the exit status, so tests call it directly.

Every subcommand lives in :mod:`omnibot.apps`: a module declares its arguments and the handler does
the work (importing heavy modules lazily so ``omnibot --help`` stays fast). A command whose arguments
are declared in a heavy module is added with :func:`~omnibot.apps.subcommands.command_in` or
:func:`~omnibot.apps.subcommands.lazy`: a placeholder with its summary until the command is chosen
(:class:`~omnibot.apps.subcommands.Commands`), so that no command imports another's modules
(``tests/cli/test_startup.py`` checks ``--help``). The
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
import os
import select
import sys
import traceback
from collections.abc import Callable, Sequence

from omnibot import __version__, collector
from omnibot.apps.demo import add_demo, add_tour
from omnibot.apps.robot import add_kinematics, add_robot
from omnibot.apps.sim import add_sim
from omnibot.apps.subcommands import Adder, Commands, add_debug_to, command_in, lazy
from omnibot.errors import ConfigError, KinematicsError, OmnibotError, ProtocolError
from omnibot.extras import missing_extra

EXIT_OK, EXIT_FAILED, EXIT_USAGE, EXIT_BUG = 0, 1, 2, 70
EXIT_SIGINT, EXIT_SIGPIPE = 130, 141

Handler = Callable[[argparse.Namespace], int]

# --------------------------------------------------------------------------- the commands in apps/

_add_send = command_in(
    "omnibot.apps.send",
    "send",
    summary="send protocol commands, print the replies and events",
    description="Sends each command (text protocol, several per argument with ';') and prints the "
    "replies and events. Exit status 0 if every reply is OK, 1 if any is an ERROR or the link "
    "fails, 2 for bad input. Motion sent is left running when send ends normally (STOP on an "
    "error or interrupt); the protocol goes back to text. Options may go anywhere among the "
    "commands (send STATUS --port URL 'MOVE,2,40,0,0'); the commands are sent in the order given.",
)
_add_console = command_in(
    "omnibot.apps.console",
    "console",
    summary="interactive terminal for the controller protocol",
    description="Type protocol commands; replies and decoded events are printed as they come. "
    ":help lists the console's own commands. Leaving (:quit, Ctrl-D, Ctrl-C) stops the robot and "
    "puts the MODE found at the start back.",
)
_add_teleop = command_in(
    "omnibot.apps.teleop",
    "teleop",
    summary="drive the robot from a joystick (pygame) or the keyboard, with a deadman",
    description="Sends VEL with its watchdog at autorepeat_rate; letting go of the enable button, "
    "losing the pad or going quiet stops the robot. On sim:// simulated time follows the wall clock.",
)
_add_dashboard = command_in(
    "omnibot.apps.dashboard",
    "dashboard",
    summary="a web page showing the robot live (map, trail, sonars, charts) and driving it",
    description="Serves the dashboard over HTTP and a websocket; bound to 127.0.0.1 unless --host "
    "says otherwise, and then an access token is required.",
)
_add_run = command_in(
    "omnibot.apps.run",
    "run",
    summary="several front ends on one runtime: --teleop pad|keyboard, --dashboard, --follow PATH",
    description="One runtime owns the robot; each front end is a source (pad/keyboard 200, the page 100, "
    "the follower 10) arbitrated as twist_mux does; the dashboard's emergency stop overrides all.",
)
_add_ros2 = command_in(
    "omnibot.apps.ros2",
    "ros2",
    summary="robots on ROS 2 (DDS, no ROS install): cmd_vel, path, initialpose in; odom, tf, imu, ranges, "
    "joint_states, battery out",
    description="cmd_vel and path sources, an odometry reset and publishing sinks of one runtime per "
    "robot, on cyclonedds with ROS 2's conventions (pip install 'omnibot[ros2]'). ROS_DOMAIN_ID and "
    "ROS_AUTOMATIC_DISCOVERY_RANGE apply.",
)
_add_record = command_in(
    "omnibot.apps.record",
    "record",
    summary="teach a path: record the robot's odometry while it is pushed by hand or driven",
    description="Samples the robot's own pose estimate (encoders, tracking wheels, gyro) by distance or "
    "time into a path file t,x,y,theta[,v]. In the simulator a hand pushes the robot along a shape with "
    "the motors off (seed 002's teaching), or VEL commands drive it; with --port it listens.",
)
_add_follow = command_in(
    "omnibot.apps.follow",
    "follow",
    summary="repeat a path: a path follower drives it, with a report and a plot",
    description="Runs a path follower at 100 Hz on the host (VEL out, TEL in); by default on the simulated "
    "robot in lockstep, measured against its ground truth. Exit status 1 if the run was not completed "
    "(the follower did not finish, or the run was outside --final-tolerance/--cross-track-tolerance).",
)
_add_map = command_in(
    "omnibot.apps.mapping",
    "map",
    summary="map a room with the robot's scanner (SLAM) while a path or a person drives it",
    description="Drives the robot along --path (or by --teleop) with the wheel-speed loop closed while the "
    "SLAM (scan matching and a pose graph with loop closures) corrects the odometry; writes the map "
    "(map_server's YAML + PGM), the trajectories (TUM) and, on the simulator, a report scored against "
    "the truth. Exit status 1 if no map was made or the path was not completed.",
)
_add_goto = command_in(
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
    importlib.import_module("omnibot.apps.calibrate_options").add_parser(sub)


_add_calibrate = lazy(
    "calibrate",
    "seed 000's power calibration (K, K_l, K_t, K_r), gyro and odometry geometry, with a report",
    _add_calibrate_now,
)


# --------------------------------------------------------------------------- parser


def _add_log_now(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    importlib.import_module("omnibot.apps.log").add_log_command(sub)


_add_log = lazy("log", "inspect, plot, export and replay a run recorded with --log FILE.mcap", _add_log_now)


def build_parser(*, full: bool = False) -> argparse.ArgumentParser:
    """The ``omnibot`` argument parser: one subcommand per entry of ``ADDERS``. The commands whose
    options live in heavy modules are declared when chosen (:class:`Commands`); ``full`` declares
    them all now."""
    parser = argparse.ArgumentParser(
        prog="omnibot", description="Drive omnidirectional mobile robots, real or simulated."
    )
    parser.add_argument("--version", action="version", version=f"omnibot {__version__}")
    parser.add_argument("--debug", action="store_true", help="show the traceback of an error")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND", action=Commands)
    for add in ADDERS:
        add(sub)
    for p in sub.choices.values():
        add_debug_to(p)
    if full:
        assert isinstance(sub, Commands)
        sub.fill_all()
    return parser


ADDERS: list[Adder] = [
    add_robot,
    add_kinematics,
    add_sim,
    add_tour,
    _add_send,
    _add_console,
    add_demo,
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
    """Run the ``omnibot`` command line (``argv``, else the process's own); returns the exit status.
    The process's own starts with the garbage collector held (:func:`omnibot.collector.starting`)."""
    if argv is not None:
        return _main(argv)
    with collector.starting():
        return _main(None)


def _main(argv: Sequence[str] | None) -> int:
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
