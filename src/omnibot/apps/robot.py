"""``omnibot robot`` (the presets, a robot's summary, its URDF) and ``omnibot kinematics`` (wheel
speeds for a body twist, or the twist for wheel speeds): the robot's description on the command line.

Light to import (``omnibot robot list`` loads none of the heavy modules: ``tests/cli/test_startup.py``);
each handler imports what it needs.
"""

from __future__ import annotations

import argparse
import json
import math
import re
import sys
from collections.abc import Sequence
from pathlib import Path

from omnibot.errors import ConfigError


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


def accept_negative_numbers(parser: argparse.ArgumentParser) -> None:
    """Take option values such as ``-0.2,0,0`` or ``-1e-3`` as values, not as unknown options (argparse
    before 3.14 takes only ``-1`` and ``-.5``). For parsers with no option that looks like a number."""
    if hasattr(parser, "_negative_number_matcher"):
        parser._negative_number_matcher = _NEGATIVE_NUMBERS


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


def add_robot(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """``omnibot robot list|show|urdf``."""
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


def add_kinematics(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """``omnibot kinematics``: ``--twist`` or ``--wheels``, negative numbers taken as values."""
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
