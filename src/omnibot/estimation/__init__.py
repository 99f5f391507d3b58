"""State estimation from the robot's own sensors (encoders, gyro); depends on robot and plain data only.
Names load on first use, each with its own module.

::

    from omnibot.estimation import make_estimator

    estimator = make_estimator("fused", robot)

Modules: ``estimator`` (the Estimator protocol, PoseEstimator), ``seed002`` (Seed002Estimator),
``registry`` (estimators by name, replay),
``odometry`` (wheel odometry, encoder counts), ``tracking`` (tracking wheels), ``heading`` (the gyro
heading filter), ``silence`` (a gyro gone quiet), ``creep`` (the floor's creep coefficients and the
wheels' creep rows, without numpy), ``slip`` (the floor's slip model and its fit), ``slipprobe``,
``spins`` (gyro bias from spins and standstills), ``stall`` (a stalled robot), ``wheelslip`` (one wheel slipping, from the fit residual).
"""

from typing import TYPE_CHECKING

from omnibot.faces import lazy_names

if TYPE_CHECKING:
    from omnibot.estimation.creep import CreepRows, SlipError, SlipParameters, creep_rows
    from omnibot.estimation.estimator import Estimator, PoseEstimator, SensorSample
    from omnibot.estimation.heading import HeadingFilter, HeadingFilterConfig
    from omnibot.estimation.odometry import WheelOdometry, compose_arc, forward_twist
    from omnibot.estimation.registry import ESTIMATORS, estimator_names, make_estimator, replay
    from omnibot.estimation.seed002 import Seed002Estimator
    from omnibot.estimation.silence import GyroSilence
    from omnibot.estimation.slip import (
        SlipLeg,
        SlipModel,
        fit_slip,
        leg_error,
        leg_residual,
    )
    from omnibot.estimation.slipprobe import SlipProbe
    from omnibot.estimation.spins import Spin, SpinFit, Standstill, fit_spins, spin_biases
    from omnibot.estimation.stall import Stall, StallDetector, StallSample
    from omnibot.estimation.tracking import Seed002Odometry, TrackingGeometry, TrackingOdometry
    from omnibot.estimation.wheelslip import WheelSlipCheck

__all__ = [
    "ESTIMATORS",
    "CreepRows",
    "Estimator",
    "GyroSilence",
    "HeadingFilter",
    "HeadingFilterConfig",
    "PoseEstimator",
    "Seed002Estimator",
    "Seed002Odometry",
    "SensorSample",
    "SlipError",
    "SlipLeg",
    "SlipModel",
    "SlipParameters",
    "SlipProbe",
    "Spin",
    "SpinFit",
    "Stall",
    "StallDetector",
    "StallSample",
    "Standstill",
    "TrackingGeometry",
    "TrackingOdometry",
    "WheelOdometry",
    "WheelSlipCheck",
    "compose_arc",
    "creep",
    "creep_rows",
    "estimator",
    "estimator_names",
    "fit_slip",
    "fit_spins",
    "forward_twist",
    "heading",
    "leg_error",
    "leg_residual",
    "make_estimator",
    "odometry",
    "registry",
    "replay",
    "seed002",
    "silence",
    "slip",
    "slipprobe",
    "spin_biases",
    "spins",
    "stall",
    "tracking",
    "wheelslip",
]

if not TYPE_CHECKING:  # type checkers take each name from its import above
    __getattr__ = lazy_names(
        __name__,
        {
            "creep": (
                "CreepRows",
                "SlipError",
                "SlipParameters",
                "creep_rows",
            ),
            "estimator": (
                "Estimator",
                "PoseEstimator",
                "SensorSample",
            ),
            "registry": (
                "ESTIMATORS",
                "estimator_names",
                "make_estimator",
                "replay",
            ),
            "seed002": ("Seed002Estimator",),
            "heading": (
                "HeadingFilter",
                "HeadingFilterConfig",
            ),
            "odometry": (
                "WheelOdometry",
                "compose_arc",
                "forward_twist",
            ),
            "silence": ("GyroSilence",),
            "slip": (
                "SlipLeg",
                "SlipModel",
                "fit_slip",
                "leg_error",
                "leg_residual",
            ),
            "slipprobe": ("SlipProbe",),
            "spins": (
                "Spin",
                "SpinFit",
                "Standstill",
                "fit_spins",
                "spin_biases",
            ),
            "stall": (
                "Stall",
                "StallDetector",
                "StallSample",
            ),
            "tracking": (
                "Seed002Odometry",
                "TrackingGeometry",
                "TrackingOdometry",
            ),
            "wheelslip": ("WheelSlipCheck",),
        },
    )
"""Each name loads its own module on first use: the core (the client, the firmware config) takes
``SlipParameters`` and ``creep_rows`` without numpy."""
