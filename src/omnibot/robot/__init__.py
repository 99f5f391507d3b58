"""Robot descriptions: the YAML model, presets, kinematics and the physical specs they hold.

::

    from omnibot.robot import RobotDescription, load_robot, preset_names

Modules: ``description`` (RobotDescription and its specs, loading and presets), ``battery`` (charge
levels of each chemistry), ``courses`` (folding courses onto a wheel layout's axes), ``summary``
(describe), ``urdf`` (to_urdf), ``kinematics`` (wheel matrices and frames: import the module).
``describe`` and ``to_urdf`` load on first use: ``omnibot robot list`` need not load XML.
"""

from importlib import import_module
from typing import TYPE_CHECKING, Any

from omnibot.robot.battery import battery_level, open_voltage
from omnibot.robot.description import (
    BatterySpec,
    CalibrationSpec,
    ControllerSpec,
    CourseTable,
    EncoderSpec,
    Footprint,
    GyroSpec,
    LimitsSpec,
    MotorEncoderSpec,
    MotorMapSpec,
    MotorSpec,
    PiecewiseLinear,
    ReachSpec,
    RobotDescription,
    RollerDragSpec,
    RollerSpec,
    ScannerSpec,
    SonarSpec,
    TrackingWheelSpec,
    WheelSpec,
    calibration_for,
    course_axes,
    load_description,
    load_robot,
    parse_description,
    preset_names,
)

if TYPE_CHECKING:
    from omnibot.robot.summary import describe
    from omnibot.robot.urdf import to_urdf

_LAZY = {"describe": "summary", "to_urdf": "urdf"}

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
    "course_axes",
    "courses",
    "describe",
    "description",
    "kinematics",
    "load_description",
    "load_robot",
    "open_voltage",
    "parse_description",
    "preset_names",
    "summary",
    "to_urdf",
    "urdf",
]


def __getattr__(name: str) -> Any:
    """``describe`` and ``to_urdf``, imported on first use."""
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return getattr(import_module(f"{__name__}.{module}"), name)
