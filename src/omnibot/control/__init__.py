"""Motion control on the host: PID, paths (files, teach, geometry, speed profile) and path followers.

Depends on the robot description and plain data only (no client, no simulator): the navigation
glue (:mod:`omnibot.navigation`) feeds followers estimates and sends their commands.

::

    from omnibot.control import make_follower, read_path

Modules: ``paths`` (Path, files, teach, geometry, the speed profile and its limits, the standard paths),
``followers`` (the Follower interface, its registry and the built-in followers), ``reach`` (how
fast the motors drive the robot on a floor), ``pid``.
"""

from typing import TYPE_CHECKING

from omnibot.faces import lazy_names

if TYPE_CHECKING:  # the names __getattr__ gives, for type checkers
    from omnibot.control.followers.base import (
        OFF_PATH,
        STOP,
        Command,
        Follower,
        State,
        correction_speed,
        follower_names,
        make_follower,
        to_body,
        wrap,
    )
    from omnibot.control.paths.files import read_path, write_path
    from omnibot.control.paths.geometry import resample
    from omnibot.control.paths.limits import Grip, MotionLimits, grip_share, grip_table
    from omnibot.control.paths.path import Path
    from omnibot.control.paths.profile import min_traversal_time, time_optimal_profile
    from omnibot.control.paths.standard import standard_path
    from omnibot.control.paths.teach import PathRecorder
    from omnibot.control.reach import floor_course_rate, free_wheel_speeds

_EXPORTS = {
    "followers.base": (
        "OFF_PATH",
        "STOP",
        "Command",
        "Follower",
        "State",
        "correction_speed",
        "follower_names",
        "make_follower",
        "to_body",
        "wrap",
    ),
    "paths.files": ("read_path", "write_path"),
    "paths.geometry": ("resample",),
    "paths.path": ("Path",),
    "paths.limits": ("Grip", "MotionLimits", "grip_share", "grip_table"),
    "paths.profile": ("min_traversal_time", "time_optimal_profile"),
    "paths.standard": ("standard_path",),
    "paths.teach": ("PathRecorder",),
    "reach": ("floor_course_rate", "free_wheel_speeds"),
}

__all__ = [
    "OFF_PATH",
    "STOP",
    "Command",
    "Follower",
    "Grip",
    "MotionLimits",
    "Path",
    "PathRecorder",
    "State",
    "correction_speed",
    "floor_course_rate",
    "follower_names",
    "followers",
    "free_wheel_speeds",
    "grip_share",
    "grip_table",
    "make_follower",
    "min_traversal_time",
    "paths",
    "pid",
    "reach",
    "read_path",
    "resample",
    "standard_path",
    "time_optimal_profile",
    "to_body",
    "wrap",
    "write_path",
]

# a name loads only its own subpackage, not the planner's reach or every follower
if not TYPE_CHECKING:  # type checkers take each name from its import above
    __getattr__ = lazy_names(__name__, _EXPORTS)
