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

from omnibot.cliargs import (
    DeprecatedAlias,
    add_robot_options,
    check_distinct,
    check_sim_options,
    recording_of,
    seed_of,
    sim_robot,
    world_of,
)
from omnibot.errors import ConfigError
from omnibot.outputs import check_writable

if TYPE_CHECKING:
    from omnibot.calibration import AccuracyPlan, CalibrationResult, Plan, Verdict
    from omnibot.client import ClientRecording, RobotClient
    from omnibot.progress import Progress
    from omnibot.robot import RobotDescription

SIM_SURFACES = ("wood", "carpet")
"""Seed 000 calibrated on wood and carpet and averaged them."""


def add_parser(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Add ``omnibot calibrate`` and its options to ``sub``."""
    p = sub.add_parser(
        "calibrate",
        help="seed 000's power calibration (K, K_l, K_t, K_r), gyro and odometry geometry, with a report",
        description="Drives calibration runs over the protocol (POWER sweeps on the courses the robot's "
        "symmetry leaves distinct: 0..45 on omni4, 0..30 on omni3, 0..90 on mecanum4; and in rotation, curved MOVEs, a rotation test, UMBmark squares), measures each by the chosen ground "
        "truth, fits the piecewise-linear factors per surface and averaged over the surfaces, uploads them "
        "(CAL) and checks open-loop accuracy before and after. Default: the simulated robot in lockstep "
        "(sim://ROBOT?surface=S), surfaces wood and carpet.",
    )
    add_robot_options(
        p,
        surface_help="surface name(s), comma-separated (default: wood,carpet in the simulator, 'floor' on "
        "--port; with several on a real robot you are asked to move it between them)",
    )
    _add_output_options(p)
    _add_truth_options(p)
    _add_scope_options(p)
    p.set_defaults(handler=run)


def _add_output_options(p: argparse.ArgumentParser) -> None:
    """Where the report and the calibration file go, and whether a worse calibration is kept."""
    p.add_argument(
        "--out",
        metavar="DIR",
        help="directory for the report (figures and tables) and, unless --calibration says otherwise, "
        "calibration.yaml (default ./out)",
    )
    p.add_argument(
        "--calibration", metavar="FILE.yaml", help="calibration file to write (default DIR/calibration.yaml)"
    )
    p.add_argument("--report", action=DeprecatedAlias, use="--out DIR", help=argparse.SUPPRESS)
    p.add_argument(
        "--force",
        action="store_true",
        help="write (and upload) the calibration even when its own check finds it worse than before (on the "
        "whole, or on a course or ROTATE); the file says so, and the exit status is still 1",
    )


def _add_truth_options(p: argparse.ArgumentParser) -> None:
    """What measures the runs, and the simulated robot's difference from its description."""
    p.add_argument(
        "--truth",
        help="ground truth: sim | csv:FILE | encoders | sonar[:NAME] | tape (default: sim on the simulator, "
        "else encoders when every wheel has one, else tape)",
    )
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


def _add_scope_options(p: argparse.ArgumentParser) -> None:
    """Which runs, fits and checks the calibration makes."""
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


def _surfaces(text: str | None, simulated: bool) -> list[str]:
    if text is None:
        return list(SIM_SURFACES) if simulated else ["floor"]
    names = [s.strip() for s in text.split(",") if s.strip()]
    if not names or len(set(names)) != len(names):
        raise ConfigError(f"expected distinct comma-separated surface names, got {text!r}", key="--surface")
    if simulated:
        from omnibot.floor import get_surface

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
    robot: RobotDescription,
    name: str,
    seed: int,
    true_robot: RobotDescription | None,
    world: str | None = None,
    recording: ClientRecording | None = None,
) -> Callable[[str], AbstractContextManager[RobotClient]]:
    """surface -> a lockstep client on a fresh simulated robot standing on it (in ``world``, default
    empty), left stopped and in its MODE on the way out, recorded in ``recording`` (``--log``)."""

    @contextmanager
    def open_client(surface: str) -> Iterator[RobotClient]:
        from omnibot.client import RobotClient, guarded
        from omnibot.sim import SimDevice
        from omnibot.transport import LockstepLink

        url = f"sim://{name}?surface={surface}&seed={seed}" + (f"&world={world}" if world else "")
        if true_robot is None:
            client = RobotClient.open(url, robot)
        else:
            device = SimDevice(robot, true_robot=true_robot, surface=surface, seed=seed, world=world)
            client = RobotClient(LockstepLink(device, url=url), robot)
        with guarded(client, recording=recording):
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


def asked_stand(ask: Callable[[str], str]) -> Callable[[RobotClient, bool], None]:
    """The motor map's stand test on a real robot: ask the person to lift it and to put it back."""

    def lift(client: RobotClient, up: bool) -> None:
        if up:
            ask(
                "Lift the robot onto a stand so that no wheel touches anything (they will spin), then press Enter: "
            )
        else:
            ask("Put the robot back on the floor where it stood, then press Enter: ")

    return lift


def run(args: argparse.Namespace, ask: Callable[[str], str] | None = None) -> int:
    """The ``omnibot calibrate`` handler; returns the exit status. ``ask`` (default: the terminal,
    checked to be one before the robot moves) asks the operator."""
    from omnibot.calibration import calibrate, judge_calibration, write_report

    cal_file, out_dir, surfaces = _checked_options(args)
    simulated = args.port is None
    interactive = ask is None
    ask = ask or terminal_ask
    if interactive:
        check_operator(_operator_tasks(args, surfaces, simulated))
    plan, accuracy = _plans(args)
    world = world_of(args)
    with contextlib.ExitStack() as stack:
        robot, client = _robot_and_client(args, stack, world)
        if client is None:
            opener = sim_opener(
                robot,
                sim_robot(args),
                seed_of(args),
                _true_robot(args, robot),
                None if world == "empty" else world,
                recording=recording_of(args),
            )
        else:
            opener = port_opener(client, ask, placed=args.yes)
        result = calibrate(
            robot,
            surfaces,
            opener,
            truth=args.truth or _truth_chooser(robot, interactive),
            plan=plan,
            accuracy=accuracy,
            ask=ask,
            progress=tqdm_progress,
            upload=not args.no_upload,
            stand=None if args.yes else asked_stand(ask),
            recording=recording_of(args),
        )
        verdict = judge_calibration(result)
        if client is not None and not args.no_upload:
            _upload_verdict(client, robot, result, keep=verdict.better is not False or args.force)
    truth_name = result.sessions[0].truth if result.sessions else ""
    files = write_report(result, out_dir)
    print(f"omnibot calibrate: {robot.name} on {', '.join(surfaces)} (truth {truth_name})")
    _print_findings(result)
    print(f"report: {out_dir} ({', '.join(f.name for f in files)})")
    _print_verdict(verdict, several=len(result.sessions) > 1)
    return _write_file(args, cal_file, result, verdict, truth_name, uploaded=client is not None)


def _robot_and_client(
    args: argparse.Namespace, stack: contextlib.ExitStack[bool | None], world: str
) -> tuple[RobotDescription, RobotClient | None]:
    """The robot to calibrate and, on ``--port``, the client of its session (entered on ``stack``);
    in the simulator its description alone (``world`` loaded, so a bad one fails before any run)."""
    from omnibot.client import robot_session
    from omnibot.robot import load_robot

    client: RobotClient | None = None
    if args.port is None:
        robot = load_robot(sim_robot(args))
        if world != "empty":
            from omnibot.sim import load_world

            load_world(world)
    else:
        session = stack.enter_context(robot_session(args.port, args.robot, recording=recording_of(args)))
        client, robot = session.client, session.robot
    if robot.n_wheels > 4:
        raise ConfigError(
            f"{robot.name} has {robot.n_wheels} motors; POWER (the calibration runs) carries at most 4"
        )
    return robot, client


def _checked_options(args: argparse.Namespace) -> tuple[Path, Path, list[str]]:
    """The calibration file, the report's directory and the surfaces, once the options that go
    together have been checked (ConfigError otherwise)."""
    from omnibot.calibration import parse_truth_spec

    check_sim_options(args, allowed=("surface",))
    cal_file, out_dir = _outputs(args)
    check_distinct(
        [("--calibration" if args.calibration else "--out", cal_file), ("--log", args.log)],
        [("--robot", args.robot), ("--true-robot", args.true_robot)],
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
    return cal_file, out_dir, surfaces


def _operator_tasks(args: argparse.Namespace, surfaces: list[str], simulated: bool) -> list[str]:
    """What the run will ask a person at the terminal to do (none: it runs unattended)."""
    from omnibot.calibration import parse_truth_spec

    tasks = []
    if not simulated and not args.yes:
        stand = "" if args.no_motor_map else " (and on a stand, wheels in the air, for the motors)"
        tasks.append("put the robot on " + " then on ".join(surfaces) + stand)
    if args.truth is not None and parse_truth_spec(args.truth)[0] in OPERATOR_TRUTHS:
        tasks.append(f"measure every run ({args.truth} truth)")
    return tasks


def _plans(args: argparse.Namespace) -> tuple[Plan, AccuracyPlan | None]:
    """The calibration's plan and the accuracy check's (None: ``--no-check``) from the options."""
    from omnibot.calibration import AccuracyPlan, Plan

    if not args.move_length > 0:
        raise ConfigError(f"expected a positive length in m, got {args.move_length}", key="--move-length")
    base = Plan.quick() if args.quick else Plan()
    plan = replace(
        base,
        courses_deg=_courses(args.courses),
        move_length=args.move_length,
        motor_map=not args.no_motor_map,
        roller_rounds=0 if args.no_rollers else base.roller_rounds,
        slip=not args.no_slip,
    )
    check = AccuracyPlan.quick() if args.quick else AccuracyPlan()
    return plan, None if args.no_check else replace(check, length=args.move_length)


def _true_robot(args: argparse.Namespace, robot: RobotDescription) -> RobotDescription | None:
    """The robot the simulator runs when it differs from the description (``--perturb``,
    ``--true-robot``); None: the description itself."""
    from omnibot.calibration import ACCEPTANCE, perturbed_robot
    from omnibot.robot import load_robot

    if args.perturb:
        return perturbed_robot(robot, ACCEPTANCE if args.perturb == "acceptance" else args.perturb)
    if args.true_robot:
        return load_robot(args.true_robot)
    return None


def _truth_chooser(robot: RobotDescription, interactive: bool) -> Callable[[RobotClient], str]:
    """Without ``--truth``: the link's default truth (checked for an operator at the terminal if it
    needs one)."""
    from omnibot.calibration import default_truth

    def chosen_truth(client: RobotClient) -> str:
        name = default_truth(client, robot)
        if interactive and name in OPERATOR_TRUTHS:
            check_operator([f"measure every run ({name} truth: the robot has no wheel encoders)"])
        return name

    return chosen_truth


def _upload_verdict(
    client: RobotClient, robot: RobotDescription, result: CalibrationResult, keep: bool
) -> None:
    """Leave the board with the new tables of the floor it stands on (the last one) and its creep, or,
    when they are not kept, with the tables it was built with."""
    if keep:
        client.upload_calibration(result.sessions[-1].spec)
        if result.sessions[-1].slip is not None:  # its creep, for MOVEs in closed loop
            client.upload_slip(result.sessions[-1].slip.params)
    elif robot.calibration is not None:
        client.upload_calibration(robot.calibration)


def _print_findings(result: CalibrationResult) -> None:
    """The accuracy table, each floor's wheel slip and the sessions' notes."""
    from omnibot.calibration import accuracy_entries, slip_summary, summary_table

    entries = accuracy_entries(result)
    if entries:
        print(summary_table(entries))
    for s in result.sessions:
        if s.slip is not None:
            print(f"wheel slip ({s.surface}): {slip_summary(s.slip)}")
    for s in result.sessions:
        for note in s.notes:
            print(f"note ({s.surface}): {note}")


def _print_verdict(verdict: Verdict, several: bool) -> None:
    """The check's verdict: better or worse than before, and over ``several`` floors their average."""
    print(f"check: {verdict.summary}" + (" (each floor's own tables)" if several else ""))
    if verdict.worse:
        print(
            f"worse than before: {'; '.join(str(w) for w in verdict.worse)} (mean abs error of a course "
            "both ways or of ROTATE, grown beyond the check's scatter)"
        )
    if verdict.average is not None and verdict.average.better is not None:
        average = verdict.average.summary.removeprefix("mean abs error of the accuracy check: ")
        kept = (
            "kept as the file's calibration for any floor"
            if verdict.average.better
            else f"not kept, worse than none ({verdict.average.reason}): each floor keeps its own tables"
        )
        print(f"average over the floors: {average}: {kept}")


def _write_file(
    args: argparse.Namespace,
    cal_file: Path,
    result: CalibrationResult,
    verdict: Verdict,
    truth_name: str,
    uploaded: bool,
) -> int:
    """Write the calibration file unless the check found it worse (``--force`` writes it anyway) and
    say where; the exit status (1: worse than before)."""
    from omnibot.calibration import write_calibration

    if verdict.better is False:
        if verdict.hint:
            print(f"hint: {verdict.hint}")
        warning = verdict.warning
        if args.force:
            cal = write_calibration(cal_file, result, truth_name, warning=warning)
            print(f"calibration: {cal} (written anyway, --force: {warning})")
        else:
            print(
                f"calibration: not written, not kept on the controller: {warning} (--force writes it anyway)"
            )
        return 1
    cal = write_calibration(cal_file, result, truth_name)
    floors = ""
    if result.chosen is None:
        floors = (
            f" (tables per floor: {', '.join(s.surface for s in result.sessions)}; pick one with --surface, "
            f"e.g. omnibot follow --calibration {cal} --surface {result.sessions[0].surface})"
        )
    print(f"calibration: {cal}{floors}")
    if uploaded and not args.no_upload:
        print(f"controller: {result.sessions[-1].surface}'s tables uploaded (CAL)")
    return 0


def _outputs(args: argparse.Namespace) -> tuple[Path, Path]:
    """(calibration file, report directory) from ``--calibration``/``--out``, and the old spellings
    ``--out CAL.yaml --report DIR`` (deprecated)."""
    out, cal, report = args.out, args.calibration, args.report
    if out is not None and out.endswith((".yaml", ".yml")) and cal is None:
        print(
            "omnibot: warning: --out CAL.yaml is deprecated; use --calibration CAL.yaml (--out is now the "
            "report's directory)",
            file=sys.stderr,
        )
        cal, out = out, report
    elif report is not None:
        if out is not None:
            raise ConfigError("give the report's directory once: --out DIR (--report is its old name)")
        out = report
    out_dir = Path(out or "out")
    cal_file = Path(cal) if cal else out_dir / "calibration.yaml"
    if cal:
        check_writable(cal_file, "--calibration")
    try:
        out_dir.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ConfigError(f"cannot make directory {out_dir}: {exc.strerror or exc}", key="--out") from None
    return cal_file, out_dir
