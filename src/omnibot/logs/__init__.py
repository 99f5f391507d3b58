"""Logs people open in their own tools: MCAP recording (ROS 2 messages), inspection, offline replay.

``recorder`` writes a run (``--log FILE.mcap``); ``reader`` reads one back (also one cut short by a
crash); ``info``, ``plot``, ``export``, ``replay`` are ``omnibot log``'s subcommands.

Other packages take the names below from this face::

    from omnibot.logs import Recorder, load_run, open_recording

``schemas`` (the ROS 2 message types) is imported as a module; ``recover`` is imported from its
module, as its function bears the module's name (a face cannot give it: the submodule shadows it).

Each loads on first use, with only the module that defines it: ``omnibot --help`` loads no MCAP or
rosbags.
"""

from typing import TYPE_CHECKING

from omnibot.faces import lazy_names

if TYPE_CHECKING:  # the names __getattr__ gives, for type checkers
    from omnibot.logs.device import RecordedDevice
    from omnibot.logs.follower_replay import (
        RecordedFollower,
        make_replayed,
        parse_options,
        recorded_followers,
        replay_follower,
    )
    from omnibot.logs.recorder import Recorder
    from omnibot.logs.recording import Recording, open_recording
    from omnibot.logs.replay import replay_log, truth_in_frame
    from omnibot.logs.rosmsg import header, map_to_odom, occupancy_grid, quaternion, stamp, vector
    from omnibot.logs.run import Run, keyword_counts, load_run, rate_and_gap
    from omnibot.logs.schemas import type_hash, typestore
    from omnibot.logs.slamscore import Frames, score_slam_logs
    from omnibot.logs.topics import IMU, JOINT_STATES, MAP, ODOM, RANGE_PREFIX, ROBOT_DESCRIPTION, SCAN, TF

_EXPORTS = {
    "device": ("RecordedDevice",),
    "follower_replay": (
        "RecordedFollower",
        "make_replayed",
        "parse_options",
        "recorded_followers",
        "replay_follower",
    ),
    "recorder": ("Recorder",),
    "recording": ("Recording", "open_recording"),
    "replay": ("replay_log", "truth_in_frame"),
    "rosmsg": ("header", "map_to_odom", "occupancy_grid", "quaternion", "stamp", "vector"),
    "run": ("Run", "keyword_counts", "load_run", "rate_and_gap"),
    "schemas": ("type_hash", "typestore"),
    "slamscore": ("Frames", "score_slam_logs"),
    "topics": ("IMU", "JOINT_STATES", "MAP", "ODOM", "RANGE_PREFIX", "ROBOT_DESCRIPTION", "SCAN", "TF"),
}

__all__ = [
    "IMU",
    "JOINT_STATES",
    "MAP",
    "ODOM",
    "RANGE_PREFIX",
    "ROBOT_DESCRIPTION",
    "SCAN",
    "TF",
    "Frames",
    "RecordedDevice",
    "RecordedFollower",
    "Recorder",
    "Recording",
    "Run",
    "device",
    "follower_replay",
    "header",
    "keyword_counts",
    "load_run",
    "make_replayed",
    "map_to_odom",
    "occupancy_grid",
    "open_recording",
    "parse_options",
    "quaternion",
    "rate_and_gap",
    "recorded_followers",
    "recorder",
    "recording",
    "recover",
    "replay",
    "replay_follower",
    "replay_log",
    "rosmsg",
    "run",
    "schemas",
    "score_slam_logs",
    "slamscore",
    "stamp",
    "topics",
    "truth_in_frame",
    "type_hash",
    "typestore",
    "vector",
]

# a name loads its own module only: a topic's name or the recording loads no MCAP or rosbags
if not TYPE_CHECKING:  # type checkers take each name from its import above
    __getattr__ = lazy_names(__name__, _EXPORTS)
