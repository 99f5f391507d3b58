"""``omnibot dashboard``: serve the live dashboard for a robot (docs/dashboard.md).

Imports here are light (no FastAPI): :func:`add_arguments` runs whenever ``omnibot`` builds its parser.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time
from typing import TYPE_CHECKING, TypedDict

from omnibot.errors import ConfigError

if TYPE_CHECKING:
    from omnibot.web import Dashboard

TOKEN_ENV = "OMNIBOT_DASHBOARD_TOKEN"


def add_server_options(p: argparse.ArgumentParser, note: str = "") -> None:
    """The dashboard server's options (``--host``, ``--allow-host``, ``--http-port``, ``--token``), for
    ``omnibot dashboard`` and ``omnibot run --dashboard``; ``note`` starts each help text."""
    p.add_argument(
        "--host",
        default="127.0.0.1",
        help=f"{note}address to serve on (default 127.0.0.1: this machine only)",
    )
    p.add_argument(
        "--allow-host",
        action="append",
        default=[],
        metavar="NAME",
        help=f"{note}a name the page may be opened by besides the bound address and the loopback names "
        "(e.g. robot.local; repeat for more); others are refused (DNS rebinding)",
    )
    p.add_argument(
        "--http-port", type=int, default=8080, help=f"{note}HTTP port (default 8080; 0: any free port)"
    )
    p.add_argument(
        "--token",
        help=f"{note}access token (default ${TOKEN_ENV}; required, and made up if not given, off loopback)",
    )


class ServerOptions(TypedDict):
    """The :class:`~omnibot.web.dashboard.Dashboard` keywords of its server options."""

    host: str
    http_port: int
    token: str | None
    allow_hosts: list[str]


def server_options(args: argparse.Namespace) -> ServerOptions:
    """The :class:`~omnibot.web.dashboard.Dashboard` keywords the server options give (the token from
    ``--token`` or ``$OMNIBOT_DASHBOARD_TOKEN``; None: made up off loopback)."""
    return ServerOptions(
        host=args.host,
        http_port=args.http_port,
        token=args.token or os.environ.get(TOKEN_ENV) or None,
        allow_hosts=args.allow_host,
    )


def add_arguments(p: argparse.ArgumentParser) -> None:
    """The ``omnibot web`` options: robot or port, address, port and access token of the dashboard."""
    from omnibot.cliargs import add_calibration_option, add_robot_options, add_wheel_loop_option

    add_robot_options(p, world="room", port_help="the simulated --robot, paced to the wall clock")
    add_wheel_loop_option(p)
    add_calibration_option(p)
    add_server_options(p)
    p.add_argument(
        "--map",
        metavar="NAME|FILE",
        help="room map to draw for a real robot: world name or YAML (sim:// shows its own)",
    )
    p.add_argument(
        "--path", metavar="FILE.csv", help="a planned path to draw: x,y rows, or a path file (t,x,y,theta)"
    )
    p.add_argument(
        "--config", metavar="FILE.yaml", help="teleop parameters for a browser gamepad (default seed 003's)"
    )
    p.add_argument(
        "--repeat-speed",
        type=float,
        default=0.3,
        metavar="V",
        help="speed cap of Repeat (following the taught path), m/s (default 0.3)",
    )
    p.add_argument("--duration", type=float, metavar="S", help="serve for S seconds (default: until Ctrl-C)")


def run(args: argparse.Namespace) -> int:
    """Run ``omnibot web``: serve the dashboard for ``--duration`` s or until interrupted; the exit
    status (1 when the robot link ended)."""
    from omnibot.cliargs import calibrated_floor, check_sim_options, recording_of, sim_url, use_calibration
    from omnibot.navigation import PathTeacher
    from omnibot.robot import RobotDescription
    from omnibot.teleop import load_teleop_config
    from omnibot.web import Dashboard, load_path

    if args.duration is not None and not (math.isfinite(args.duration) and args.duration > 0):
        raise ConfigError(f"expected a positive number of seconds, got {args.duration}", key="--duration")
    if not (math.isfinite(args.repeat_speed) and args.repeat_speed > 0):
        raise ConfigError(f"expected a positive speed in m/s, got {args.repeat_speed}", key="--repeat-speed")
    room_map = _room_map(args)
    check_sim_options(args)
    config = load_teleop_config(args.config)
    url = sim_url(args)
    path = load_path(args.path) if args.path else None
    server = server_options(args)

    def make_teach(robot: RobotDescription) -> PathTeacher:
        return PathTeacher(robot, period=config.period, speed=args.repeat_speed)

    dash = Dashboard(
        url,
        args.robot,
        world=room_map,
        path=path,
        config=config,
        make_teach=make_teach,
        wheel_loop=not args.open_loop,
        floor=lambda client, robot: use_calibration(args, client, robot),
        recording=recording_of(args),
        surface=calibrated_floor(args),
        **server,
    )
    dash.start()
    try:
        print(f"omnibot dashboard for {url}: {dash.url}", flush=True)
        if dash.token and not server["token"]:
            print(
                "  (an access token was made up because the server is reachable from other machines)",
                flush=True,
            )
        print("  Ctrl-C stops it (and the robot)", flush=True)
        lost = _serve(dash, args.duration)
    except KeyboardInterrupt:
        print("omnibot dashboard: stopping", flush=True)
        raise
    finally:
        dash.stop()
    if lost is not None:
        print(f"omnibot dashboard: the robot link ended: {lost}", file=sys.stderr)
        return 1
    return 0


def _room_map(args: argparse.Namespace) -> str | None:
    """``--map``; with ``--port``, ``--world`` as its deprecated old name (a warning, and ``--world``
    then taken out of ``args``)."""
    room_map: str | None = args.map
    if args.port and args.world is not None and room_map is None:
        print(
            "omnibot: warning: --world with --port is deprecated; use --map for the room map", file=sys.stderr
        )
        room_map, args.world = args.world, None
    return room_map


def _serve(dash: Dashboard, duration: float | None) -> str | None:
    """Wait while ``dash`` serves, ``duration`` s (None: until interrupted) or until its robot link
    ends; why that link ended (None: it did not)."""
    end = math.inf if duration is None else time.monotonic() + duration
    while time.monotonic() < end and dash.link.alive:
        time.sleep(min(0.2, max(0.0, end - time.monotonic())))
    return dash.link.lost
