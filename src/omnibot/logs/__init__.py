"""Logs people open in their own tools: MCAP recording (ROS 2 messages), inspection, offline replay.

``recorder`` writes a run (``--log FILE.mcap``); ``reader`` reads one back (also one cut short by a
crash); ``info``, ``plot``, ``export``, ``replay`` are ``omnibot log``'s subcommands.
"""

__all__ = [
    "device",
    "follower_replay",
    "recorder",
    "recording",
    "recover",
    "replay",
    "run",
    "schemas",
    "slamscore",
    "topics",
]
