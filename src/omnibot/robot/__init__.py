"""Robot descriptions: the YAML model, presets, kinematics and the physical specs they hold.

::

    from omnibot.robot import RobotDescription, load_robot, preset_names

Modules: ``description`` (RobotDescription, its limits and controller sections, loading and presets),
``spec`` (Spec: the sections' strict base), ``parts`` (footprint, motors, rollers, wheels, battery),
``sensors`` (encoders, gyro, sonars, scanner), ``calibration_spec`` (the calibration section and
moving it onto a robot's course axes), ``battery`` (charge
levels of each chemistry), ``courses`` (folding courses onto a wheel layout's axes), ``summary``
(describe), ``urdf`` (to_urdf), ``rows`` (the kinematics in plain Python: wheel rows, rank check,
least-squares inverse) and ``kinematics`` (the same over numpy arrays, and frames): import the module.
``describe`` and ``to_urdf`` load on first use: ``omnibot robot list`` need not load XML.
"""

from typing import TYPE_CHECKING

from omnibot.faces import lazy_names
from omnibot.robot.battery import battery_level, open_voltage
from omnibot.robot.calibration_spec import (
    CalibrationSpec,
    CourseTable,
    MotorMapSpec,
    PiecewiseLinear,
    ReachSpec,
    RollerDragSpec,
    calibration_for,
    course_axes,
)
from omnibot.robot.description import (
    ControllerSpec,
    LimitsSpec,
    RobotDescription,
    load_description,
    load_robot,
    parse_description,
    preset_names,
)
from omnibot.robot.parts import BatterySpec, Footprint, MotorSpec, RollerSpec, WheelSpec
from omnibot.robot.sensors import (
    EncoderSpec,
    GyroSpec,
    MotorEncoderSpec,
    ScannerSpec,
    SonarSpec,
    TrackingWheelSpec,
)

if TYPE_CHECKING:
    from omnibot.robot.summary import describe
    from omnibot.robot.urdf import to_urdf

__all__ = [
    "BatterySpec",
    "CalibrationSpec",
    "ControllerSpec",
    "CourseTable",
    "EncoderSpec",
    "Footprint",
    "GyroSpec",
    "LimitsSpec",
    "MotorEncoderSpec",
    "MotorMapSpec",
    "MotorSpec",
    "PiecewiseLinear",
    "ReachSpec",
    "RobotDescription",
    "RollerDragSpec",
    "RollerSpec",
    "ScannerSpec",
    "SonarSpec",
    "TrackingWheelSpec",
    "WheelSpec",
    "battery",
    "battery_level",
    "calibration_for",
    "calibration_spec",
    "course_axes",
    "courses",
    "describe",
    "description",
    "kinematics",
    "load_description",
    "load_robot",
    "open_voltage",
    "parse_description",
    "parts",
    "preset_names",
    "rows",
    "sensors",
    "spec",
    "summary",
    "to_urdf",
    "urdf",
]

if not TYPE_CHECKING:  # type checkers take each name from its import above
    __getattr__ = lazy_names(__name__, {"summary": ("describe",), "urdf": ("to_urdf",)})
"""``describe`` and ``to_urdf``, imported on first use."""
