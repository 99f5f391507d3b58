"""``omnibot calibrate``'s options: the robot, where the report and the calibration file go, what
measures the runs, and which runs, fits and checks it makes (the command: :mod:`omnibot.apps.calibrate`).
"""

from __future__ import annotations

import argparse

from omnibot.apps.calibrate import run
from omnibot.cliargs import DeprecatedAlias, add_robot_options


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
