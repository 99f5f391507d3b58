"""Re-run an estimator offline on a log's telemetry, to tune it without driving again.

The telemetry is taken from the protocol lines (``/omnibot/protocol``, the TEL events exactly as the
controller sent them, in protocol integers), decoded by the same code the client decodes them with,
and fed to the estimator the recorder ran (or another one). With the recorded estimator, the
estimate is the live one, bit for bit: :func:`replay_log` compares it with ``odom``.

The simulator's truth is in world coordinates; an estimate is in the frame it was started in (the
origin, or the pose a runtime started it at: the path's first pose for ``run --follow``, where the
simulated robot stands wherever its world puts it). :func:`truth_in_frame` moves the truth into the
estimate's frame (the truth at the replay's first sample onto the estimator's start pose), so the
two are compared where they mean the same.
"""

from __future__ import annotations

import bisect
import math
from dataclasses import dataclass, field

from omnibot.client import Telemetry
from omnibot.errors import ConfigError
from omnibot.estimation import make_estimator
from omnibot.logs.run import PoseRow, Run
from omnibot.logs.topics import ADOPTED
from omnibot.motion import Estimate, Pose2D
from omnibot.protocol import text
from omnibot.protocol.messages import Telemetry as TelMessage
from omnibot.robot import RobotDescription


@dataclass(frozen=True)
class Replay:
    """A log's telemetry run through an estimator again: its estimates and how far they are from the
    recorded ones."""

    estimator: str
    recorded_estimator: str
    estimates: list[tuple[float, Estimate]]
    """(log time s, estimate) after each telemetry sample that carried encoders."""
    max_difference: float | None
    """Largest distance (m) and heading difference (rad) from the recorded estimate, whichever is
    larger; None when the log has no estimate to compare with or another estimator was run."""
    note: str = ""
    """Why the live estimate was not compared ("" when it was or there was none)."""
    start: Pose2D = field(default_factory=lambda: Pose2D(0.0, 0.0, 0.0))
    """Where the replayed estimator started (its frame's pose at the first sample)."""


def robot_of(run: Run) -> RobotDescription:
    """The robot description a log carries; ConfigError when it has none."""
    description = run.description()
    if description is None:
        raise ConfigError(
            f"{run.path} has no robot description (omnibot metadata): cannot replay", key="FILE"
        )
    return RobotDescription.model_validate(description)


def telemetry_of(run: Run) -> list[Telemetry]:
    """The TEL events of the run, decoded as the client decoded them live."""
    out = []
    for t, direction, keyword, line in run.protocol:
        if direction != "event" or keyword != "TEL":
            continue
        message = text.parse_line(line.encode("ascii"))
        if isinstance(message, TelMessage):
            out.append(Telemetry.from_message(message, t))
    return out


def replay_log(run: Run, estimator: str | None = None) -> Replay:
    """Run ``estimator`` (default: the one recorded) over the run's telemetry."""
    adopted = run.metadata.get(ADOPTED)
    recorded = adopted["name"] if adopted else run.omnibot_metadata().get("estimator", "")
    name = estimator or recorded
    if not name:
        raise ConfigError(f"{run.path} names no estimator: give --estimator", key="--estimator")
    samples = [tel for tel in telemetry_of(run) if tel.encoders is not None]
    live = run.estimate_exact
    start: Pose2D | None = None
    if adopted:
        # the estimate is a runtime's (the follower's), from its start pose and from the sample
        # after which it was adopted; before that the recorder's own estimator wrote it
        x, y, theta = (float(v) for v in adopted["start"].split())
        start = Pose2D(x, y, theta)
        samples = samples[int(adopted["samples"]) :]
        live = live[int(adopted["estimates"]) :]
    start = start or Pose2D(0.0, 0.0, 0.0)
    est = make_estimator(name, robot_of(run), start)
    estimates = [(tel.time, est.update(tel)) for tel in samples]
    difference: float | None = None
    note = ""
    if name == recorded and live and adopted and adopted.get("slip"):
        note = "not compared with the live estimate: it corrected for a floor's slip, which the log does not hold"
    elif name == recorded and live:
        offline = [e for _, e in estimates]
        if adopted:  # the runtime may have ended before the recording (the session's last samples)
            offline = offline[: len(live)]
        difference = _max_difference(live, offline)
    return Replay(name, recorded, estimates, difference, note, start)


def truth_in_frame(run: Run, replay: Replay) -> list[tuple[float, float, float, float]]:
    """The run's truth (t, x, y, theta) from the replay's first sample on, in the replayed estimate's
    frame: moved so that the truth at that sample stands at the estimator's start pose (empty without
    truth or samples)."""
    if not run.truth or not replay.estimates:
        return []
    t0 = replay.estimates[0][0]
    rows = run.truth[max(0, bisect.bisect_left([r[0] for r in run.truth], t0) - 1) :]
    anchor = min(rows[:2], key=lambda r: abs(r[0] - t0))  # the truth read with the first sample
    return [(r[0], *_moved(r, anchor, replay.start)) for r in rows if r[0] >= anchor[0]]


def _moved(row: PoseRow, anchor: PoseRow, start: Pose2D) -> tuple[float, float, float]:
    """``row``'s pose seen from ``anchor``, placed at ``start``: start o anchor^-1 o row."""
    turn = start.theta - anchor[3]
    c, s = math.cos(turn), math.sin(turn)
    dx, dy = row[1] - anchor[1], row[2] - anchor[2]
    return (start.x + c * dx - s * dy, start.y + s * dx + c * dy, row[3] + turn)


def _max_difference(live: list[tuple[float, float, float, float]], offline: list[Estimate]) -> float:
    """The largest of the position (m) and heading (rad) differences; inf if the counts differ."""
    if len(live) != len(offline):
        return math.inf
    worst = 0.0
    for (_, x, y, theta), e in zip(live, offline, strict=True):
        worst = max(worst, math.hypot(x - e.x, y - e.y), abs(theta - e.theta))
    return worst
