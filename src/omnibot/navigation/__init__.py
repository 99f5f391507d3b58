"""Teach and repeat on a robot: the follower loop over a client, metrics, plots, the CLI commands.

The glue between :mod:`omnibot.client` (VEL out, TEL in), :mod:`omnibot.estimation` and
:mod:`omnibot.control`; see docs/navigation.md.
"""

__all__ = [
    "explore",
    "following",
    "goto",
    "goto_source",
    "judge",
    "metrics",
    "plot",
    "record",
    "runner",
    "session",
    "slipcal",
    "webteach",
]
