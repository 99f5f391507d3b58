"""``omnibot calibrate``: the glue between links, the session and the outputs (its options:
:mod:`omnibot.apps.calibrate_options`; the robots it drives: :mod:`omnibot.apps.calibrate_robots`).

Kept light at import time (``omnibot --help`` imports it): everything heavy is imported in
:func:`run`.
"""

from __future__ import annotations

import argparse
import contextlib
import math
import sys
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING

from omnibot.apps.calibrate_robots import (
    OPERATOR_TRUTHS,
    asked_stand,
    check_operator,
    port_opener,
    sim_opener,
    terminal_ask,
)
from omnibot.cliargs import (
    check_distinct,
    check_sim_options,
    recording_of,
    seed_of,
    sim_robot,
    world_of,
)
from omnibot.errors import ConfigError
from omnibot.outputs import check_directory, check_writable

if TYPE_CHECKING:
    from omnibot.calibration import AccuracyPlan, CalibrationResult, Plan, Verdict
    from omnibot.client import RobotClient
    from omnibot.progress import Progress
    from omnibot.robot import RobotDescription

SIM_SURFACES = ("wood", "carpet")
"""Seed 000 calibrated on wood and carpet and averaged them."""


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
    _say_figures_left_out()
    _print_verdict(verdict, several=len(result.sessions) > 1)
    return _write_file(args, cal_file, result, verdict, truth_name, uploaded=client is not None)


def _say_figures_left_out() -> None:
    """The report's figures need matplotlib: where it is missing, say which extra draws them."""
    from omnibot.plots import unavailable

    why = unavailable()
    if why is not None:
        print(f"report: figures left out: {why}")


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
    check_directory(out_dir, "--out")  # made by the report (and the calibration file) when written
    return cal_file, out_dir
