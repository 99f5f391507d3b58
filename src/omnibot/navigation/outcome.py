"""What a taught path and a follow run must achieve, in plain Python: ``omnibot record`` and ``omnibot
follow`` declare their options from these without the ``control`` extra's numpy."""

from __future__ import annotations

from dataclasses import dataclass

MIN_POINTS = 10
"""A recording with fewer points is no path to follow (``omnibot record`` exits 1)."""

MIN_LENGTH = 0.10
"""m: nor is one shorter than this."""


@dataclass(frozen=True)
class Tolerances:
    """What a follow run must achieve to count as done (``omnibot follow`` exits 1 otherwise): end
    within ``final`` m of the path's end and never stray more than ``cross_track`` m from the path.
    The defaults hold with room to spare for the trackers on every preset and floor the simulator has,
    and catch a run that went astray (a wrong robot, a lost link, a latched emergency stop)."""

    final: float = 0.15
    cross_track: float = 0.30
