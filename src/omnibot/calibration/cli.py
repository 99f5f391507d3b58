"""``omnibot calibrate``: argument parsing and the glue between links, the session and the outputs.

Kept light at import time (``omnibot --help`` imports it): everything heavy is imported in
:func:`run`.
"""

from __future__ import annotations

import argparse
import contextlib
import math
import sys
from collections.abc import Callable, Iterator
from contextlib import AbstractContextManager, contextmanager
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING

from omnibot.errors import ConfigError

if TYPE_CHECKING:
    from omnibot.client.client import RobotClient
    from omnibot.progress import Progress
    from omnibot.robot.description import RobotDescription

SIM_SURFACES = ("wood", "carpet")
"""Seed 000 calibrated on wood and carpet and averaged them."""


def add_parser(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    p = sub.add_parser(
        "calibrate",
        help="seed 000's power calibration (K, K_l, K_t, K_r), gyro and odometry geometry, with a report",
        description="Drives calibration runs over the protocol (POWER sweeps on courses 0..45 and in "
        "rotation, curved MOVEs, a rotation test, UMBmark squares), measures each by the chosen ground "
        "truth, fits the piecewise-linear factors per surface and averaged over the surfaces, uploads them "
        "(CAL) and checks open-loop accuracy before and after. Default: the simulated robot in lockstep "
        "(sim://ROBOT?surface=S), surfaces wood and carpet.",
    )
    p.add_argument("--port", help="link URL of the controller (default: the simulator in lockstep)")
    p.add_argument("--robot", default="omni4", help="preset name or description file (default omni4)")
    p.add_argument(
        "--surface",
        help="surface name(s), comma-separated (default: wood,carpet in the simulator, 'floor' on --port; "
        "with several on a real robot you are asked to move it between them)",
    )
    p.add_argument("--out", required=True, metavar="CAL.yaml", help="calibration file to write")
    p.add_argument("--report", required=True, metavar="DIR", help="directory for the figures and tables")
    p.add_argument(
        "--truth",
        help="ground truth: sim | csv:FILE | encoders | sonar[:NAME] | tape (default: sim on the simulator, "
        "else encoders when every wheel has one, else tape)",
    )
    p.add_argument("--seed", type=int, default=0, help="simulator seed (default 0)")
    sim = p.add_mutually_exclusive_group()
    sim.add_argument(
        "--perturb",
        metavar="SPEC",
        help="simulate a robot that differs from its description, e.g. 'radius=1.05;torque_constant=1.1,0.9,0.9,1.1' "
        "('acceptance' for that one)",
    )
    sim.add_argument(
        "--true-robot", metavar="FILE", help="simulate this description while the firmware uses --robot"
    )
    p.add_argument(
        "--quick", action="store_true", help="seed 000's scope: courses 0 and 45, fewer runs and checks"
    )
    p.add_argument(
        "--courses", help="calibrated courses in degrees, comma-separated (default: 4 over the fold range)"
    )
    p.add_argument(
        "--move-length", type=float, default=1.0, help="MOVE length the fit is exact for, m (default 1)"
    )
    p.add_argument(
        "--no-motor-map", action="store_true", help="no per-motor offsets and gains (seed 000's factors only)"
    )
    p.add_argument(
        "--no-rollers",
        action="store_true",
        help="no roller drag term for the wheels that stand still on the motor axes (seed 000's factors only)",
    )
    p.add_argument(
        "--no-slip",
        action="store_true",
        help="skip the wheel-slip runs (the driven-wheel odometry's creep on each floor)",
    )
    p.add_argument(
        "--yes",
        action="store_true",
        help="unattended on --port: the robot already stands on the (one) surface, with room around it, so "
        "nobody is asked to place it (needs a truth that needs no operator: not tape)",
    )
    p.add_argument("--no-check", action="store_true", help="skip the before/after accuracy moves")
    p.add_argument(
        "--no-upload", action="store_true", help="fit only: do not upload (no K_t runs, no after-check)"
    )
    p.set_defaults(handler=run)


def _surfaces(text: str | None, simulated: bool) -> list[str]:
    if text is None:
        return list(SIM_SURFACES) if simulated else ["floor"]
    names = [s.strip() for s in text.split(",") if s.strip()]
    if not names or len(set(names)) != len(names):
        raise ConfigError(f"expected distinct comma-separated surface names, got {text!r}", key="--surface")
    if simulated:
        from omnibot.sim.surfaces import get_surface

        for name in names:
            try:
                get_surface(name)
            except ConfigError as exc:
                raise ConfigError(str(exc), key="--surface") from None
    return names


def _courses(text: str | None) -> tuple[float, ...] | None:
    if text is None:
        return None
    try:
        values = tuple(float(v) for v in text.split(","))
    except ValueError:
        raise ConfigError(f"expected comma-separated degrees, got {text!r}", key="--courses") from None
    if not values or not all(math.isfinite(v) for v in values):
        raise ConfigError(f"expected comma-separated degrees, got {text!r}", key="--courses")
    return values


@contextmanager
def tqdm_progress(desc: str, total: int) -> Iterator[Progress | None]:
    """A tqdm bar of runs on stderr (hidden when stderr is not a terminal)."""
    from omnibot.progress import progress_bar

    with progress_bar(desc, total, unit="run") as bar:
        yield bar


def sim_opener(
    robot: RobotDescription, name: str, seed: int, true_robot: RobotDescription | None
) -> Callable[[str], AbstractContextManager[RobotClient]]:
    """surface -> a lockstep client on a fresh simulated robot standing on it."""

    @contextmanager
    def open_client(surface: str) -> Iterator[RobotClient]:
        from omnibot.client.client import RobotClient

        if true_robot is None:
            with RobotClient.open(f"sim://{name}?surface={surface}&seed={seed}", robot) as client:
                yield client
            return
        from omnibot.sim.device import SimDevice
        from omnibot.transport.lockstep import LockstepLink

        device = SimDevice(robot, true_robot=true_robot, surface=surface, seed=seed)
        with RobotClient(
            LockstepLink(device, url=f"sim://{name}?surface={surface}&seed={seed}"), robot
        ) as client:
            yield client

    return open_client


OPERATOR_TRUTHS = ("tape",)
"""Truth strategies that ask a person to measure every run."""


def terminal_ask(prompt: str) -> str:
    """``input(prompt)``; ConfigError (not EOFError) when standard input ends."""
    try:
        return input(prompt)
    except EOFError:
        raise ConfigError(f"standard input ended while asking: {prompt.strip()!r}", key="calibrate") from None


def check_operator(reasons: list[str]) -> None:
    """ConfigError when the run needs someone at a terminal (``reasons``) and stdin is not one."""
    if reasons and not sys.stdin.isatty():
        raise ConfigError(
            f"needs a terminal to ask you to {' and to '.join(reasons)} (standard input is not one); "
            "run it on a terminal, or unattended with --yes and a truth that needs no operator",
            key="calibrate",
        )


def port_opener(
    client: RobotClient, ask: Callable[[str], str], placed: bool = False
) -> Callable[[str], AbstractContextManager[RobotClient]]:
    """surface -> the one real controller, after asking the person to put the robot there (except on
    the first surface when the robot is ``placed`` there already)."""
    where: dict[str, str | None] = {"surface": None}  # where the robot stands

    @contextmanager
    def open_client(surface: str) -> Iterator[RobotClient]:
        if where["surface"] is None and placed:
            where["surface"] = surface
        if where["surface"] != surface:
            ask(f"Put the robot on {surface} with about 2 m of free floor around it, then press Enter: ")
            where["surface"] = surface
        yield client

    return open_client


def run(args: argparse.Namespace, ask: Callable[[str], str] | None = None) -> int:
    """The ``omnibot calibrate`` handler; returns the exit status. ``ask`` (default: the terminal,
    checked to be one before the robot moves) asks the operator."""
    from omnibot.calibration.accuracy import AccuracyPlan
    from omnibot.calibration.calfile import write_calibration
    from omnibot.calibration.experiments import Plan
    from omnibot.calibration.perturb import ACCEPTANCE, perturbed_robot
    from omnibot.calibration.report import accuracy_entries, slip_summary, write_report
    from omnibot.calibration.session import calibrate
    from omnibot.calibration.tables import summary_table
    from omnibot.calibration.truth import default_truth, parse_truth_spec
    from omnibot.client.client import RobotClient
    from omnibot.robot.description import load_robot

    robot = load_robot(args.robot)
    if robot.n_wheels > 4:
        raise ConfigError(
            f"{robot.name} has {robot.n_wheels} motors; POWER (the calibration runs) carries at most 4"
        )
    simulated = args.port is None
    if not simulated and (args.perturb or args.true_robot):
        raise ConfigError("--perturb and --true-robot need the simulator (leave out --port)")
    surfaces = _surfaces(args.surface, simulated)
    if args.truth is not None:
        parse_truth_spec(args.truth)
    if args.yes and simulated:
        raise ConfigError("only for a robot on --port (the simulator asks nothing)", key="--yes")
    if args.yes and len(surfaces) > 1:
        raise ConfigError("several surfaces need someone to move the robot between them", key="--yes")
    operator = []
    if not simulated and not args.yes:
        operator.append("put the robot on " + " then on ".join(surfaces))
    if args.truth is not None and parse_truth_spec(args.truth)[0] in OPERATOR_TRUTHS:
        operator.append(f"measure every run ({args.truth} truth)")
    interactive = ask is None
    ask = ask or terminal_ask
    if interactive:
        check_operator(operator)
    if not args.move_length > 0:
        raise ConfigError(f"expected a positive length in m, got {args.move_length}", key="--move-length")
    base = Plan.quick() if args.quick else Plan()
    courses = _courses(args.courses)
    plan = replace(
        base,
        courses_deg=courses,
        move_length=args.move_length,
        motor_map=not args.no_motor_map,
        roller_rounds=0 if args.no_rollers else base.roller_rounds,
        slip=not args.no_slip,
    )
    check = AccuracyPlan.quick() if args.quick else AccuracyPlan()
    accuracy = None if args.no_check else replace(check, length=args.move_length)
    true_robot = None
    if args.perturb:
        true_robot = perturbed_robot(robot, ACCEPTANCE if args.perturb == "acceptance" else args.perturb)
    elif args.true_robot:
        true_robot = load_robot(args.true_robot)

    def chosen_truth(client: RobotClient) -> str:
        """The default truth of the link (checked for an operator at the terminal if it needs one)."""
        name = default_truth(client, robot)
        if interactive and name in OPERATOR_TRUTHS:
            check_operator([f"measure every run ({name} truth: the robot has no wheel encoders)"])
        return name

    truth: str | Callable[[RobotClient], str] = args.truth or chosen_truth

    with contextlib.ExitStack() as stack:
        client: RobotClient | None = None
        if simulated:
            opener = sim_opener(robot, str(args.robot), args.seed, true_robot)
        else:
            client = stack.enter_context(RobotClient.open(args.port, robot))
            opener = port_opener(client, ask, placed=args.yes)
        result = calibrate(
            robot,
            surfaces,
            opener,
            truth=truth,
            plan=plan,
            accuracy=accuracy,
            ask=ask,
            progress=tqdm_progress,
            upload=not args.no_upload,
        )
        if client is not None and result.average is not None and not args.no_upload:
            client.upload_calibration(result.average)  # the averaged table stays on the real board
    truth_name = result.sessions[0].truth if result.sessions else ""
    cal = write_calibration(args.out, result, truth_name)
    files = write_report(result, args.report)
    print(f"omnibot calibrate: {robot.name} on {', '.join(surfaces)} (truth {truth_name})")
    entries = accuracy_entries(result)
    if entries:
        print(summary_table(entries))
    for s in result.sessions:
        if s.slip is not None:
            print(f"wheel slip ({s.surface}): {slip_summary(s.slip)}")
    for s in result.sessions:
        for note in s.notes:
            print(f"note ({s.surface}): {note}")
    print(f"calibration: {cal}")
    print(f"report: {Path(args.report)} ({', '.join(f.name for f in files)})")
    return 0
