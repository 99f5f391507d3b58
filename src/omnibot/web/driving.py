"""Driving from the page: its stick, keys and gamepad as teleop samples, and the ``drive`` part of
the state frame (who drives, why, at what twist)."""

from __future__ import annotations

import math
from typing import Any

from omnibot.motion import Twist
from omnibot.runtime import Cycle
from omnibot.teleop import (
    JoyState,
    Sample,
    TeleopConfig,
    TwistLimits,
    axes_tuple,
    fractions_to_twist,
    joy_to_command,
    limit_twist,
)
from omnibot.web.messages import Drive, Joy

DRIVE_RATE_MAX = math.pi
"""rad/s at full turn from the page (keys, slider): half a turn a second, whatever the robot could do."""
PAGE_PRIORITY = 100
"""The page's driving in arbitration: above the repeat (10), so it takes over and hands back."""


def drive_limits(limits: TwistLimits) -> TwistLimits:
    """Full scale of the page's keys, stick and turn slider: the robot's, the turn at most
    :data:`DRIVE_RATE_MAX`."""
    return TwistLimits(limits.speed, min(limits.rate, DRIVE_RATE_MAX))


def page_sample(
    request: Drive | Joy, config: TeleopConfig, limits: TwistLimits, drive: TwistLimits, now: float
) -> tuple[Sample, str]:
    """The deadman sample of a page's input at ``now`` and the input's name: a Drive's fractions of
    ``drive`` (the page's full scale), a Joy's axes and buttons through the teleop mapping of
    ``config``, within ``limits``."""
    if isinstance(request, Drive):
        twist = fractions_to_twist(request.vx, request.vy, request.w, drive)
        return Sample(twist, request.enable, now), request.source
    # the Gamepad API's axes are up/left negative, ROS joy's positive
    joy = JoyState(axes_tuple([-a for a in request.axes]), tuple(int(b > 0.5) for b in request.buttons), now)
    cmd = joy_to_command(config, joy)
    return Sample(limit_twist(cmd.twist, limits), cmd.enabled, now), "gamepad"


def _rounded(twist: Twist | None) -> list[float] | None:
    return None if twist is None else [round(v, 3) for v in (twist.vx, twist.vy, twist.w)]


def drive_state(
    cycle: Cycle, state: str, source: str, twist: Twist | None, ended: str | None, teach: bool
) -> dict[str, Any]:
    """The state frame's ``drive``: ``state`` (estop, the page's deadman phase, following, idle),
    the page's input ``source``, who is in control after ``cycle`` and why, the latched stop, the
    ``twist`` shown and the one achieved, why the page's last drive ``ended``, ``teach`` offered."""
    decision = cycle.decision
    return {
        "state": state,
        "source": source,
        "control": decision.source,
        "reason": decision.reason,
        "latched": cycle.latched,
        "latch_reason": cycle.latch_reason,
        "twist": _rounded(twist),
        "achieved": _rounded(cycle.achieved),
        "ended": ended,
        "teach": teach,
    }
