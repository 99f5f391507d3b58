"""Command sources: whatever proposes a body twist each cycle (a person, a follower, a script).

A source is any object with a ``name``, a ``priority`` (0-255, higher wins), a ``timeout`` (s a
proposal stays active in arbitration) and ``propose(cycle) -> Proposal | None``; ``watchdog`` (the
VEL timeout for its commands, s) is optional. Sources never touch the client: the runtime sends.

A person's sources (a pad, the keyboard, the page's stick: :class:`~omnibot.teleop.DeadmanSource`
and :class:`~omnibot.teleop.PadSource`, through teleop's mapping and deadman) are teleop's; ROS 2's
``cmd_vel`` is the bridge's. A proposal marked :attr:`Proposal.fresh` (a person who let go of the
deadman and pressed it again) asks the runtime to release a latched emergency stop.

* :class:`FollowerSource`: a path follower (repeat). The hand-back policy: while another source or a
  lock has the robot, the follower stands by (its controller is not updated, so nothing winds up);
  when the robot comes back to it, it resumes from where the robot now is, driving straight back to
  the path's nearest point ahead of the progress made (if farther than ``APPROACH_GAP``) and then
  along the rest. ``on_override="stop"`` ends the run at the first override instead. An emergency
  stop (a lock of priority 255), a refused command, a latched emergency stop on the controller, a
  stall (:mod:`omnibot.runtime.stall`) or the robot farther from the path than the follower chases
  (:attr:`~omnibot.control.Follower.off_path`: a push, a localiser's correction) end the run
  (:attr:`FollowerSource.failure`): nothing drives off on its own after one. Its ``frame`` (the ``map -> odom`` correction of a SLAM or a localiser)
  has it steer by the estimate moved into the map frame, the path's, instead of the odometry's.
* :class:`ScriptSource`: twists from a function of time (scripts, tests, demos, the navigator's
  scripted manoeuvres: ``record --teach drive``, the gyro spin, the slip runs); like a follower it
  ends at a refused command or an emergency stop.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Literal, Protocol

import numpy as np

from omnibot.control import Follower, Path
from omnibot.motion import Estimate, Pose2D, Twist
from omnibot.runtime.cycle import Cycle

APPROACH_GAP = 0.02
"""m: farther than this from the path, a follower that gets the robot back first drives straight to it."""


@dataclass(frozen=True)
class Proposal:
    """A source's twist for this cycle; ``fresh``: a person just pressed the deadman again (the
    runtime then releases a latched emergency stop with STOP before the VEL)."""

    twist: Twist
    fresh: bool = False


class Source(Protocol):
    """What the runtime asks of a command source (see the module docstring)."""

    name: str
    priority: int
    timeout: float

    def propose(self, cycle: Cycle) -> Proposal | None:
        """This cycle's twist, or None when the source has nothing to say."""
        ...


class FollowerSource:
    """Follows ``path`` with ``follower`` (see the module docstring for the hand-back policy)."""

    def __init__(
        self,
        follower: Follower,
        path: Path,
        *,
        name: str = "follower",
        priority: int = 10,
        watchdog: float = 0.15,
        on_override: Literal["resume", "stop"] = "resume",
        frame: Callable[[], Pose2D | None] | None = None,
    ) -> None:
        self.name = name
        self.frame = frame
        """The path's frame in the odometry's, ``map -> odom`` now (None, or a call giving None: the
        estimate as it is)."""
        self.priority = priority
        self.wait_reply = False  # 100 Hz: replies are collected at the next cycle
        self.follower = follower
        self.path = path
        self.watchdog = watchdog
        self.timeout = max(2.0 * follower.dt, 0.05)
        self.on_override = on_override
        self.started = False
        self.finished = False
        self.failure = ""
        """Why the run ended early ("" while running or when it completed)."""
        self.state: Estimate | None = None
        """The state the follower last steered by."""
        self.twist: Twist | None = None
        self.accel = 0.0
        """m/s^2: the follower's planned rate of change of its last proposal's speed (the runtime
        sends it with the VEL to a controller that takes it)."""
        self.body_accel: tuple[float, float, float] | None = None
        """The follower's planned acceleration of the body for its last proposal (m/s^2 along the
        body's axes, rad/s^2; None: no plan), sent with the VEL to a controller of version 4."""
        self.overrides = 0
        """How often another source or a lock took the robot from it."""
        self._standing_by = False
        self._driven = False  # it has had the robot at least once
        self._s = 0.0  # progress along self.path, m

    @property
    def completed(self) -> bool:
        """The follower reached the path's end (not ended early)."""
        return self.finished and not self.failure and self.follower.done

    def start(self, t: float) -> None:
        """Start the follower on the path at time ``t`` (done by the first cycle otherwise)."""
        self.follower.start(self.path, t)
        self.started = True

    def end(self, why: str = "") -> None:
        """End the run; ``why`` (if not empty) says why it ended early."""
        self.finished = True
        self.failure = self.failure or why

    def propose(self, cycle: Cycle) -> Proposal | None:
        """The follower's twist, a stand-by zero while overridden, None once finished."""
        if self.finished:
            return None
        why = must_end(cycle, self.name)
        if why:
            self.end(why)
            return None
        state = cycle.estimate
        if state is None:
            return None
        correction = self.frame() if self.frame is not None else None
        if correction is not None:
            state = moved(state, correction)
        if not self.started:
            self.start(state.t)
        previous = cycle.decision
        if previous.source not in ("", self.name) or previous.lock:
            if self.on_override == "stop":
                self.end(f"stopped: {previous.reason}")
                return None
            if not self._standing_by:
                self.overrides += self._driven
                self._standing_by = True
            self.accel = 0.0
            self.body_accel = None
            return Proposal(Twist())  # stand by: ready to take the robot (back)
        if self._standing_by:
            self._standing_by = False
            if self._driven:
                self._resume(state)
            else:  # it never had the robot: start now, on the whole path
                self.follower.start(self.path, state.t)
            if self.finished:
                return None
        self._driven = self._driven or previous.source == self.name  # the arbiter gave it the robot
        command = self.follower.update(state)
        self.state = state
        if self.follower.done or self.follower.failure:
            self.end(self.follower.failure)
            return None
        self._s = self.path.project_near(state.x, state.y, self._s).s if len(self.path) > 1 else 0.0
        self.twist = Twist(command.vx, command.vy, command.w)
        self.accel = self.follower.planned_accel
        self.body_accel = self.follower.planned_body_accel
        return Proposal(self.twist)

    def _resume(self, state: Estimate) -> None:
        """Start again on the rest of the path, from where the robot now is."""
        rest = remainder(self.path, self._s, state)
        if rest is None:
            self.end()
            return
        self.follower.start(rest, state.t)


def moved(state: Estimate, t: Pose2D) -> Estimate:
    """``state`` (pose and world-frame velocity) in the frame where the estimate's frame is at ``t``."""
    c, s = math.cos(t.theta), math.sin(t.theta)
    return Estimate(
        state.t,
        t.x + c * state.x - s * state.y,
        t.y + s * state.x + c * state.y,
        state.theta + t.theta,
        c * state.vx - s * state.vy,
        s * state.vx + c * state.vy,
        state.w,
        state.slipping,
        state.standstill,
    )


def must_end(cycle: Cycle, name: str) -> str:
    """Why a source that drives on its own (a follower, a script) must end now, "" for no reason: an
    error notice concerning it (a command of its own refused, a stall the stall watch found), the
    controller's latched emergency stop, or an emergency stop lock (nothing drives off on its own
    after one)."""
    for notice in cycle.notices:
        if notice.source == name and notice.level == "error":
            return notice.text
    if cycle.latched:
        if cycle.latch_reason == "battery":
            return "battery stop latched on the controller (battery flat)"
        return "emergency stop latched on the controller"
    if cycle.decision.estop:
        return f"stopped: {cycle.decision.reason}"
    return ""


def remainder(path: Path, s: float, state: Estimate) -> Path | None:
    """The path from the nearest point ahead of arc length ``s`` (the progress made) on, with a
    straight run from the robot's pose in front when it is farther than ``APPROACH_GAP``; None when
    less than a point is left."""
    proj = path.project_near(state.x, state.y, s, behind=0.0, ahead=0.5)
    i = proj.index + 1
    if i >= len(path):
        return None
    cols: dict[str, Any] = {
        "x": np.concatenate(([proj.x], path.x[i:])),
        "y": np.concatenate(([proj.y], path.y[i:])),
        "theta": np.concatenate(([path.theta[i - 1]], path.theta[i:])),
    }
    if path.v is not None:
        cols["v"] = np.concatenate(([path.v[i - 1]], path.v[i:]))
    if math.hypot(proj.x - state.x, proj.y - state.y) > APPROACH_GAP:
        cols = {
            "x": np.concatenate(([state.x], cols["x"])),
            "y": np.concatenate(([state.y], cols["y"])),
            "theta": np.concatenate(([state.theta], cols["theta"])),
            **({"v": np.concatenate(([cols["v"][0]], cols["v"]))} if "v" in cols else {}),
        }
    return Path(**cols)


class ScriptSource:
    """Twists from ``script(t)``, ``t`` s on the cycle's clock since its first cycle (None: nothing
    to say); it ends when the script returns :data:`END`, or early (:attr:`failure` says why) when a
    command of its own is refused, the controller latches its emergency stop or an emergency stop
    lock engages."""

    END = "end"

    def __init__(
        self,
        script: Callable[[float], Twist | str | None],
        *,
        name: str = "script",
        priority: int = 50,
        timeout: float = 0.5,
        watchdog: float = 0.25,
    ) -> None:
        self.name = name
        self.priority = priority
        self.timeout = timeout
        self.watchdog = watchdog
        self.script = script
        self.finished = False
        self.failure = ""
        """Why the script ended early ("" while running or when it ran to its end)."""
        self._t0: float | None = None

    def propose(self, cycle: Cycle) -> Proposal | None:
        """The script's twist at the cycle's time since the first cycle (None: nothing to say)."""
        if self.finished:
            return None
        self.failure = must_end(cycle, self.name)
        if self.failure:
            self.finished = True
            return None
        if self._t0 is None:
            self._t0 = cycle.now
        out = self.script(cycle.now - self._t0)
        if isinstance(out, str):
            self.finished = True
            return None
        return None if out is None else Proposal(out)
