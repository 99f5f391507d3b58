"""Seed 000's power calibration, automated, with gyro and odometry-geometry calibration (docs/calibration.md).

Other packages take the entry points from this face, each loaded on first use with only the module
that defines it (so ``omnibot --help`` stays light)::

    from omnibot.calibration import calibrate, calibrate_surface       # the whole procedure
    from omnibot.calibration import Plan, AccuracyPlan                 # how much to measure, the check
    from omnibot.calibration import CalibrationResult, Verdict         # what it produced, how good
    from omnibot.calibration import load_calibration, write_calibration, merge_calibration
    from omnibot.calibration import TRUTHS, register_truth             # ground-truth strategies

Data flow: RobotClient -> experiments, motors, rollers, check (POWER/MOVE/ROTATE runs, each measured
by a truth strategy into a runs.RunResult) -> the pure fits (fits: rate curves -> K, K_l, K_r,
curved MOVEs -> K_t; motorfit, rollerfit, gyro, umbmark) -> CAL upload -> results -> calfile, report,
verdict. The fits, plans, results and file format import no client (tests/test_imports.py).
"""

from typing import TYPE_CHECKING

from omnibot.faces import lazy_names

if TYPE_CHECKING:  # the names __getattr__ gives, for type checkers
    from omnibot.calibration.accuracy import AccuracyPlan
    from omnibot.calibration.calfile import (
        apply_calibration,
        floor_calibration,
        load_calibration,
        merge_calibration,
        write_calibration,
    )
    from omnibot.calibration.perturb import ACCEPTANCE, parse_perturbation, perturbed_robot
    from omnibot.calibration.plan import Plan
    from omnibot.calibration.report import accuracy_entries, slip_summary, write_report
    from omnibot.calibration.results import CalibrationResult
    from omnibot.calibration.session import calibrate, calibrate_surface
    from omnibot.calibration.tables import summary_table
    from omnibot.calibration.truth import TRUTHS, SimTruth, default_truth, parse_truth_spec, register_truth
    from omnibot.calibration.verdict import Verdict, judge_calibration

_EXPORTS = {
    "accuracy": ("AccuracyPlan",),
    "calfile": (
        "apply_calibration",
        "floor_calibration",
        "load_calibration",
        "merge_calibration",
        "write_calibration",
    ),
    "perturb": ("ACCEPTANCE", "parse_perturbation", "perturbed_robot"),
    "plan": ("Plan",),
    "report": ("accuracy_entries", "slip_summary", "write_report"),
    "results": ("CalibrationResult",),
    "session": ("calibrate", "calibrate_surface"),
    "tables": ("summary_table",),
    "truth": ("TRUTHS", "SimTruth", "default_truth", "parse_truth_spec", "register_truth"),
    "verdict": ("Verdict", "judge_calibration"),
}

__all__ = [
    "ACCEPTANCE",
    "TRUTHS",
    "AccuracyPlan",
    "CalibrationResult",
    "Plan",
    "SimTruth",
    "Verdict",
    "accuracy",
    "accuracy_entries",
    "apply_calibration",
    "calfile",
    "calibrate",
    "calibrate_surface",
    "default_truth",
    "floor_calibration",
    "judge_calibration",
    "load_calibration",
    "merge_calibration",
    "parse_perturbation",
    "parse_truth_spec",
    "perturb",
    "perturbed_robot",
    "plan",
    "register_truth",
    "report",
    "results",
    "session",
    "slip_summary",
    "summary_table",
    "tables",
    "truth",
    "verdict",
    "write_calibration",
    "write_report",
]

# a name loads the module that defines it: the plan and the file (pure modules) load no client
if not TYPE_CHECKING:  # type checkers take each name from its import above
    __getattr__ = lazy_names(__name__, _EXPORTS)
