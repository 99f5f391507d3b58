"""Teach and repeat on a robot: the follower loop over a client, metrics, plots, the CLI commands.

The glue between :mod:`omnibot.client` (VEL out, TEL in), :mod:`omnibot.estimation` and
:mod:`omnibot.control`; see docs/navigation.md.

Other packages take the names below from this face::

    from omnibot.navigation import FollowOptions, GotoOptions, follow_path, simulated_client

Each loads on first use, with only the module that defines it (the slip calibration needs no planner,
teach and repeat no map). A function named as its module cannot be given (the submodule shadows it):
``goto.goto`` is called on the module (``from omnibot.navigation import goto``), and ``explore`` and
its ``GOTO`` options are imported from their module, whose names the face leaves alone (as are
``views``', exploring's view goals).
"""

from typing import TYPE_CHECKING

from omnibot.faces import lazy_names

if TYPE_CHECKING:  # the names __getattr__ gives, for type checkers
    from omnibot.navigation.brake import BrakeSource
    from omnibot.navigation.following import FOLLOWER_PRIORITY, follower_source
    from omnibot.navigation.goal import GotoOptions, GotoResult, PoseProvider, ScanSource
    from omnibot.navigation.goto import navigation_runtime
    from omnibot.navigation.goto_source import GotoSource
    from omnibot.navigation.judge import FollowJudge
    from omnibot.navigation.outcome import MIN_LENGTH, MIN_POINTS, Tolerances
    from omnibot.navigation.plot import plot_run
    from omnibot.navigation.record import check_recording, teach
    from omnibot.navigation.runner import STANDSTILL, Navigator
    from omnibot.navigation.scanwatch import ScanPoints
    from omnibot.navigation.session import FollowOptions, follow_path, simulated_client, summary, verdict
    from omnibot.navigation.slipcal import SLIP_COURSES, SlipCalibration, calibrate_slip
    from omnibot.navigation.trace import FollowRun
    from omnibot.navigation.webteach import PathTeacher

_EXPORTS = {
    "brake": ("BrakeSource",),
    "following": ("FOLLOWER_PRIORITY", "follower_source"),
    "goal": ("GotoOptions", "GotoResult", "PoseProvider", "ScanSource"),
    "goto": ("navigation_runtime",),
    "goto_source": ("GotoSource",),
    "judge": ("FollowJudge",),
    "plot": ("plot_run",),
    "outcome": ("MIN_LENGTH", "MIN_POINTS", "Tolerances"),
    "record": ("check_recording", "teach"),
    "runner": ("STANDSTILL", "Navigator"),
    "scanwatch": ("ScanPoints",),
    "session": ("FollowOptions", "follow_path", "simulated_client", "summary", "verdict"),
    "slipcal": ("SLIP_COURSES", "SlipCalibration", "calibrate_slip"),
    "trace": ("FollowRun",),
    "webteach": ("PathTeacher",),
}

__all__ = [
    "FOLLOWER_PRIORITY",
    "MIN_LENGTH",
    "MIN_POINTS",
    "SLIP_COURSES",
    "STANDSTILL",
    "BrakeSource",
    "FollowJudge",
    "FollowOptions",
    "FollowRun",
    "GotoOptions",
    "GotoResult",
    "GotoSource",
    "Navigator",
    "PathTeacher",
    "PoseProvider",
    "ScanPoints",
    "ScanSource",
    "SlipCalibration",
    "Tolerances",
    "brake",
    "calibrate_slip",
    "check_recording",
    "explore",
    "follow_path",
    "follower_source",
    "following",
    "goal",
    "goto",
    "goto_source",
    "judge",
    "metrics",
    "navigation_runtime",
    "outcome",
    "plot",
    "plot_run",
    "record",
    "runner",
    "scanwatch",
    "session",
    "simulated_client",
    "slipcal",
    "summary",
    "teach",
    "trace",
    "verdict",
    "views",
    "webteach",
]

# a name loads its own module only: the slip calibration loads no planner, no dashboard
if not TYPE_CHECKING:  # type checkers take each name from its import above
    __getattr__ = lazy_names(__name__, _EXPORTS)
