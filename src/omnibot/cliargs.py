"""One grammar for every command that talks to a robot: ``--robot --port --seed --world --surface``.

:func:`add_robot_options` declares them the same way on every command (same meaning, same
defaults); :func:`sim_url` turns them into the ``sim://`` URL of the simulated robot a command
drives when no ``--port`` is given. The defaults:

* ``--robot``: the robot the controller names in its HELLO (``sim://PRESET`` names its preset);
  with no ``--port`` the simulated robot is :data:`DEFAULT_ROBOT`. A ``--robot`` that names another
  robot than the link's is refused (:func:`omnibot.client.session.robot_on_link`).
* ``--port``: the simulated ``--robot`` (in lockstep, in-process; ``omnibot demo``: on a pty).
* ``--seed``: :data:`DEFAULT_SEED`; ``--world``: ``empty`` unless a command needs walls (``demo``,
  ``teleop``, ``dashboard``: ``room``); ``--surface``: the world's floor. These three shape the
  simulated robot only: given with ``--port`` they are refused (put them in a ``sim://`` URL), so
  nothing the user asked for is silently ignored.

``--out`` is a directory wherever a command writes several files; a single output file is named for
what it is (``record --path FILE``, ``calibrate --calibration FILE``). :class:`DeprecatedAlias` keeps
old spellings working with a warning. ``--debug`` (every command) shows the traceback of an error.
"""

from __future__ import annotations

import argparse
import math
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any, cast

from omnibot.errors import ConfigError
from omnibot.outputs import check_writable

if TYPE_CHECKING:
    from omnibot.apps.recording import CommandRecording

DEFAULT_ROBOT = "omni4"
DEFAULT_SEED = 1
SIM_ONLY = ("seed", "world", "surface")


class DeprecatedAlias(argparse.Action):
    """An old spelling of an option: stores into the new one's ``dest`` and says it is deprecated."""

    def __init__(self, option_strings: Sequence[str], dest: str, *, use: str, **kwargs: Any) -> None:
        self.use = use
        super().__init__(option_strings, dest, **kwargs)

    def __call__(
        self,
        parser: argparse.ArgumentParser,
        namespace: argparse.Namespace,
        values: Any,
        option_string: str | None = None,
    ) -> None:
        """Warn on stderr that the old spelling is deprecated, then store the value as the new option does."""
        print(f"omnibot: warning: {option_string} is deprecated; use {self.use}", file=sys.stderr)
        setattr(namespace, self.dest, self.const if self.nargs == 0 else values)


def add_wheel_loop_option(p: argparse.ArgumentParser) -> None:
    """``--open-loop`` on every command that drives through the runtime (``follow``, ``teleop``,
    ``dashboard``, ``ros2``, ``run``): by default the controller's wheel-speed loop is closed on the
    motor encoders (:class:`~omnibot.runtime.runtime.Runtime`'s ``wheel_loop``)."""
    p.add_argument(
        "--open-loop",
        action="store_true",
        help="drive without the controller's wheel-speed loop (default: closed where every motor has an "
        "encoder); the robot then goes as fast as the floor and the power calibration let it",
    )


OFF_PATH_HELP = 0.5
"""The default ``--off-path`` the help names (the followers' ``OFF_PATH``; a test keeps them equal,
this module importing no follower)."""


def add_off_path_option(p: argparse.ArgumentParser, prefix: str = "") -> None:
    """``--off-path M`` on the commands that follow a path (``follow``, ``run --follow``): the follower's
    ``off_path`` (:data:`omnibot.control.followers.base.OFF_PATH` by default)."""
    p.add_argument(
        "--off-path",
        type=float,
        metavar="M",
        help=f"{prefix}how far from the path (m) the follower still steers back (default {OFF_PATH_HELP}, "
        "Nav2's bound); farther, it stops and the run ends NOT COMPLETED",
    )


def off_path_options(args: argparse.Namespace) -> dict[str, float]:
    """The follower options ``--off-path`` gives: ``{"off_path": M}``, or none (the default)."""
    if args.off_path is None:
        return {}
    return {"off_path": positive(args.off_path, "--off-path")}


def add_calibration_option(p: argparse.ArgumentParser) -> None:
    """``--calibration CAL.yaml`` on the runtime's front ends (``teleop``, ``dashboard``, ``ros2``,
    ``run``); :func:`use_calibration` applies it."""
    p.add_argument(
        "--calibration",
        metavar="CAL.yaml",
        help="calibration file from `omnibot calibrate` (of this robot): the floor's (--surface) tables are "
        "uploaded (CAL), and its wheel slip corrects the odometry and every VEL, so the body goes at the "
        "speed asked",
    )


def use_calibration(args: argparse.Namespace, client: Any, robot: Any) -> Any:
    """``--calibration``: upload the floor's (``--surface``) tables and creep to ``client``'s
    controller (CAL; the creep's table where the controller knows it: a closed-loop MOVE's landing
    takes it out); the floor's wheel-slip model for ``robot``
    (:class:`~omnibot.estimation.slip.SlipModel`), None without the option."""
    path = getattr(args, "calibration", None)
    if not path:
        return None
    from omnibot.calibration import floor_calibration
    from omnibot.estimation import SlipModel

    tables, slip = floor_calibration(path, robot, args.surface)
    if tables is not None:
        client.upload_calibration(tables)
    client.upload_slip(slip)
    return SlipModel(robot, slip)


def calibrated_floor(args: argparse.Namespace) -> str | None:
    """The floor a front end's ramp keeps within the grip of
    (:meth:`~omnibot.teleop.TwistLimits.from_limits`): ``--surface`` with a ``--calibration``, whose
    wheel slip the runtime asks on top of each twist; None without one (the simulator's floor alone:
    without the floor's slip asked the whole accelerations settle sooner, BENCHMARKS.md)."""
    if not getattr(args, "calibration", None):
        return None
    surface: str | None = getattr(args, "surface", None)
    return surface


def add_debug_option(p: argparse.ArgumentParser) -> None:
    """``--debug`` on a (sub)command; SUPPRESS keeps ``omnibot --debug CMD`` working too."""
    p.add_argument(
        "--debug", action="store_true", default=argparse.SUPPRESS, help="show the traceback of an error"
    )


def add_robot_options(
    p: argparse.ArgumentParser,
    *,
    world: str = "empty",
    port_help: str = "the simulated --robot in lockstep (sim://ROBOT?seed=...)",
    surface_help: str = "",
    several: bool = False,
) -> None:
    """``--robot --port --seed --world --surface`` with the shared meaning and defaults (``several``:
    ``--port`` may be repeated, one robot each; ``args.port`` is then a list or None)."""
    p.add_argument(
        "--robot",
        metavar="PRESET|FILE",
        help=f"the robot (default: the one the controller names; {DEFAULT_ROBOT} in the simulator); "
        "it must be the robot on the link",
    )
    p.add_argument(
        "--port",
        metavar="URL",
        action="append" if several else "store",
        help=f"link URL of the controller (default: {port_help})"
        + ("; repeat for more robots" if several else ""),
    )
    p.add_argument(
        "--seed", type=int, metavar="N", help=f"simulator seed (default {DEFAULT_SEED}; not with --port)"
    )
    p.add_argument(
        "--world",
        metavar="NAME|FILE",
        help=f"simulated world: empty, room, corridor, house, long_corridor or a YAML file (default {world}; not with --port)",
    )
    p.add_argument(
        "--surface",
        metavar="NAME",
        help=surface_help
        or "simulated floor: wood, carpet, concrete, linoleum (default: the world's; not with --port)",
    )
    add_log_option(p)
    p.set_defaults(default_world=world)


def add_log_option(p: argparse.ArgumentParser) -> None:
    """``--log FILE.mcap``: record the run (:mod:`omnibot.logs.recorder`; ``omnibot log``);
    ``--foxglove [[HOST:]PORT]`` (``--foxglove-token``): serve it live to Foxglove
    (:mod:`omnibot.logs.live`)."""
    p.add_argument(
        "--log",
        metavar="FILE.mcap",
        help="record the run: link bytes, protocol, telemetry, estimate, truth, URDF (MCAP, ROS 2 messages)",
    )
    p.add_argument(
        "--foxglove",
        nargs="?",
        const="8765",
        metavar="[HOST:]PORT",
        help="serve the same channels live to Foxglove on ws://HOST:PORT (default 127.0.0.1:8765; "
        "an access token off loopback)",
    )
    p.add_argument(
        "--foxglove-token",
        metavar="TOKEN",
        help="--foxglove: access token (default $OMNIBOT_FOXGLOVE_TOKEN; required, and made up if not "
        "given, off loopback)",
    )


def recording_of(args: argparse.Namespace) -> CommandRecording | None:
    """The command's ``--log`` / ``--foxglove`` recording, which :func:`omnibot.cli.main` opened for
    it (:mod:`omnibot.apps.recording`): the command hands it to its sessions and runtimes. None: it
    records nothing (or it was called without ``main``)."""
    return cast("CommandRecording | None", getattr(args, "recording", None))


def check_sim_options(args: argparse.Namespace, allowed: Sequence[str] = ()) -> None:
    """With ``--port``, ``--seed/--world/--surface`` (those not in ``allowed``) are refused; with a
    ``--calibration`` ``--surface`` names the floor whose tables and slip apply."""
    if getattr(args, "port", None) is None:
        return
    if getattr(args, "calibration", None):
        allowed = (*allowed, "surface")
    given = [
        f"--{name}" for name in SIM_ONLY if name not in allowed and getattr(args, name, None) is not None
    ]
    if given:
        verb, them = ("shapes", "it") if len(given) == 1 else ("shape", "them")
        raise ConfigError(
            f"{', '.join(given)} {verb} the simulated robot; with --port put {them} in a sim:// URL "
            "(sim://omni4?seed=1&world=room&surface=wood)",
            key=given[0],
        )


def check_distinct(
    outputs: Sequence[tuple[str, str | Path | None]], inputs: Sequence[tuple[str, str | Path | None]] = ()
) -> None:
    """Refuse, before anything runs, an output file that is one of the command's inputs or another
    of its outputs (the same file, by any name): writing it would destroy what the user gave (the
    path followed, the log replayed, the robot description) or one result would overwrite another.
    Each file comes with its option as the user knows it (an input's may be its metavar, ``PATH``);
    inputs that are no existing files (a preset's name) are left out."""
    seen: dict[Path, str] = {}
    given_inputs = [(role, given) for role, given in inputs if given and Path(given).is_file()]
    for role, given in [*given_inputs, *outputs]:
        if not given:
            continue
        key = Path(given).resolve()
        if key in seen:
            raise ConfigError(f"{given} is also {seen[key]}: give another file to write", key=role)
        seen[key] = role


def check_plot(path: str | Path | None, flag: str) -> None:
    """:func:`check_writable`, and the file's extension names a format matplotlib writes (.png,
    .svg, .pdf ...): refused before the robot moves, not after it, and no ``.png`` added unasked."""
    if path is None:
        return
    check_writable(path, flag)
    from matplotlib.figure import Figure

    kinds = Figure().canvas.get_supported_filetypes()
    suffix = Path(path).suffix.lower().removeprefix(".")
    if suffix not in kinds:
        raise ConfigError(
            f"{path}: the plot's format is its extension, one of {', '.join('.' + k for k in sorted(kinds))}",
            key=flag,
        )


def seed_of(args: argparse.Namespace) -> int:
    """The ``--seed`` given, or ``DEFAULT_SEED`` when the command has none or it was left out; a
    negative one is refused (the simulator's random streams take seeds >= 0, as ``sim://`` does)."""
    seed = getattr(args, "seed", None)
    if seed is None:
        return DEFAULT_SEED
    if int(seed) < 0:
        raise ConfigError(f"expected an integer >= 0, got {seed}", key="--seed")
    return int(seed)


def world_of(args: argparse.Namespace) -> str:
    """The simulated world's name: ``--world``, else the command's ``default_world``, else ``empty``."""
    world = getattr(args, "world", None)
    return str(world if world is not None else getattr(args, "default_world", "empty"))


def sim_robot(args: argparse.Namespace) -> str:
    """The simulated robot when no ``--port`` is given."""
    robot = getattr(args, "robot", None)
    return str(robot) if robot else DEFAULT_ROBOT


def simulated(args: argparse.Namespace) -> bool:
    """The robot is the in-process simulator: no ``--port``, or a ``sim://`` one (behind any
    ``spy+``/``faults+`` wrappers)."""
    port = getattr(args, "port", None)
    return port is None or _scheme(port) == "sim"


def physics_behind(url: str | None) -> bool:
    """The link ends in omnibot's physics: no URL (the default simulator), ``sim://`` or ``uno://``
    (the emulated UNO with the physics in the loop), behind any ``spy+``/``faults+`` wrappers. Such a
    link knows where the robot stands."""
    return url is None or _scheme(url) in ("sim", "uno")


def _scheme(url: str) -> str:
    """The scheme of the link a URL ends in, behind any ``spy+``/``faults+`` wrappers ("" for a
    device path: no ``scheme:``)."""
    scheme, colon, _ = str(url).split("+")[-1].partition(":")
    return scheme if colon else ""


def sim_url(args: argparse.Namespace) -> str:
    """``--port``, or the ``sim://`` URL of the simulated robot the options describe."""
    if getattr(args, "port", None):
        return str(args.port)
    check_world(args)
    query = f"seed={seed_of(args)}&world={world_of(args)}"
    if getattr(args, "surface", None):
        query += f"&surface={args.surface}"
    return f"sim://{sim_robot(args)}?{query}"


def check_world(args: argparse.Namespace) -> None:
    """A bad ``--world`` or ``--surface`` is reported before anything starts."""
    from omnibot.floor import SURFACES
    from omnibot.sim import load_world

    surface = getattr(args, "surface", None)
    if surface is not None and surface not in SURFACES:
        raise ConfigError(
            f"unknown surface {surface!r}; expected one of: {', '.join(SURFACES)}", key="--surface"
        )
    load_world(world_of(args))


def placed_by(exc: ConfigError, flag: str, where: str) -> ConfigError:
    """A simulated robot that cannot stand where ``flag`` put it (through the ``pose=`` of the
    ``sim://`` URL a command made of it) told as ``flag`` and ``where`` the robot was put, not as
    that URL, which the user never wrote; any other error as it is."""
    from omnibot.errors import SimulationError

    why = exc.__context__  # the simulator's own reason, which the URL's scheme restated
    if exc.key != "pose" or not isinstance(why, SimulationError):
        return exc
    return ConfigError(f"{why}: the simulated robot is put at {where}", key=flag)


def positive(value: float, flag: str) -> float:
    """``value`` if it is a positive finite number, else a ConfigError naming ``flag``."""
    if not (math.isfinite(value) and value > 0):
        raise ConfigError(f"expected a positive number, got {value:g}", key=flag)
    return value


def output_dir(text: str, flag: str = "--out") -> Path:
    """``--out DIR`` checked, not made: its writer makes it with the first file
    (:func:`omnibot.outputs.made_directory`), so a run that fails first leaves no empty directory."""
    from omnibot.outputs import check_directory

    return check_directory(text, flag)
