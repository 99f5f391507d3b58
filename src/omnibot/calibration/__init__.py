"""Seed 000's power calibration, automated, with gyro and odometry-geometry calibration (docs/calibration.md).

Entry points (imported from their modules, so ``omnibot --help`` stays light)::

    from omnibot.calibration.session import calibrate, calibrate_surface   # the whole procedure
    from omnibot.calibration.plan import Plan                                # how much to measure
    from omnibot.calibration.accuracy import AccuracyPlan                    # the before/after check
    from omnibot.calibration.results import CalibrationResult               # what it produced
    from omnibot.calibration.calfile import load_calibration, write_calibration, merge_calibration
    from omnibot.calibration.truth import TRUTHS, register_truth             # ground-truth strategies

Data flow: RobotClient -> experiments, motors, rollers, check (POWER/MOVE/ROTATE runs, each measured
by a truth strategy into a runs.RunResult) -> the pure fits (fits: rate curves -> K, K_l, K_r,
curved MOVEs -> K_t; motorfit, rollerfit, gyro, umbmark) -> CAL upload -> results -> calfile, report,
verdict. The fits, plans, results and file format import no client (tests/test_imports.py).
"""

__all__ = ["accuracy", "calfile", "perturb", "plan", "report", "session", "tables", "truth", "verdict"]
