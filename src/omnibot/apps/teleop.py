"""``omnibot teleop``: drive a robot from a joystick or the keyboard (docs/teleop.md).

Imports here are light (no pygame): :func:`add_arguments` runs whenever ``omnibot`` builds its parser.
"""

from __future__ import annotations

import argparse
import contextlib
import math
import sys
from collections.abc import Callable
from typing import Any

from omnibot.errors import ConfigError
from omnibot.extras import missing_extra


def add_arguments(p: argparse.ArgumentParser) -> None:
    """The ``omnibot teleop`` options: robot or port, input device, limits and the teleop config file."""
    from omnibot.cliargs import add_calibration_option, add_robot_options, add_wheel_loop_option

    add_robot_options(p, world="room", port_help="the simulated --robot, paced to the wall clock")
    add_wheel_loop_option(p)
    add_calibration_option(p)
    group = p.add_mutually_exclusive_group()
    group.add_argument(
        "--joystick", action="store_true", help="read a pad through pygame (waits for one to be plugged)"
    )
    group.add_argument("--keyboard", action="store_true", help="read keys in this terminal")
    p.add_argument(
        "--config", metavar="FILE.yaml", help="teleop parameters for another pad (default: seed 003's)"
    )
    p.add_argument("--duration", type=float, metavar="S", help="stop after S seconds (default: until Ctrl-C)")


def _say(text: str) -> None:
    print(f"teleop: {text}", flush=True)


def open_source(
    args: argparse.Namespace,
    config: Any,
    say: Callable[[str], None],
    options: tuple[str, str] = ("--keyboard", "--joystick"),
) -> Any:
    """The input source the flags ask for; with neither flag a pad if one is attached, else the
    keyboard if standard input is a terminal. ``options``: how the command spells the keyboard and
    the pad, named in its errors."""
    from omnibot.teleop.keyboard import KeyboardSource

    if args.keyboard:
        return KeyboardSource(config, option=options[0])
    try:
        from omnibot.teleop.joystick import JoystickSource

        pad = JoystickSource(config, on_message=say)
    except ImportError as exc:  # pygame is the teleop extra
        raise ConfigError(
            missing_extra(exc) or f"joystick input needs pygame: {exc}", key=options[1]
        ) from None
    if args.joystick or pad.attached:
        if not pad.attached:
            say("no joystick attached yet: plug one in (the robot stays still until then)")
        return pad
    pad.close()
    if not sys.stdin.isatty():
        raise ConfigError(
            f"no joystick attached and standard input is not a terminal: plug in a pad ({options[1]})"
        )
    return KeyboardSource(config, option=options[0])


def run(args: argparse.Namespace) -> int:
    """Run ``omnibot teleop`` for ``--duration`` s or until the user quits, then print what was sent;
    0 (Ctrl-C is raised again after the summary)."""
    from omnibot.apps.teleop_loop import Teleop
    from omnibot.cliargs import calibrated_floor, check_sim_options, recording_of, sim_url, use_calibration
    from omnibot.client import robot_session
    from omnibot.protocol import codes
    from omnibot.teleop import load_teleop_config
    from omnibot.teleop.keyboard import HELP
    from omnibot.transport import find_device

    if args.duration is not None and not (math.isfinite(args.duration) and args.duration > 0):
        raise ConfigError(f"expected a positive number of seconds, got {args.duration}", key="--duration")
    check_sim_options(args)
    config = load_teleop_config(args.config)
    url = sim_url(args)
    source = open_source(args, config, _say)
    recording = recording_of(args)
    interrupted: KeyboardInterrupt | None = None
    with contextlib.ExitStack() as stack:
        stack.callback(source.close)
        session = stack.enter_context(
            robot_session(url, args.robot, timeout=max(0.2, config.vel_timeout), recording=recording)
        )
        client = session.client
        if hasattr(source, "__enter__"):
            stack.enter_context(source)
        device = find_device(client.link)
        where = "simulated, paced to the wall clock" if device is not None else "real time"
        _say(
            f"{client.link.url} ({where}), {source.name}; VEL every {config.period * 1000:.0f} ms, watchdog {config.vel_timeout:g} s"
        )
        if source.name == "keyboard":
            _say(HELP)
        teleop = Teleop(
            client,
            config,
            source,
            on_message=_say,
            robot=session.robot,
            wheel_loop=not args.open_loop,
            slip=use_calibration(args, client, session.robot),
            recording=recording,
            surface=calibrated_floor(args),
        )
        _say(f"limits: {teleop.limits.speed:.2f} m/s, {teleop.limits.rate:.2f} rad/s")
        if recording is not None:  # the log holds what the robot did, not only what it was sent
            client.telemetry(max(config.period, 0.01), codes.TEL_MASK)
        try:
            teleop.run(args.duration)  # stops the robot on the way out, Ctrl-C included
        except KeyboardInterrupt as exc:  # the summary first, then the exit status says interrupted
            interrupted = exc
        if device is not None:
            p = device.sim.pose
            _say(f"robot at x={p.x:.2f} m y={p.y:.2f} m heading={round(math.degrees(p.theta))} deg")
        _say(f"sent {teleop.sent.vel} VEL, {teleop.sent.zero} zero VEL, {teleop.sent.errors} failed")
    if interrupted is not None:
        raise interrupted
    return 0
