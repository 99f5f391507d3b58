"""Re-run an estimator offline on a log's telemetry, to tune it without driving again.

The telemetry is taken from the protocol lines (``/omnibot/protocol``, the TEL events exactly as the
controller sent them, in protocol integers), decoded by the same code the client decodes them with,
and fed to the estimator the recorder ran (or another one). With the recorded estimator, the
estimate is the live one, bit for bit: :func:`replay_log` compares it with ``odom``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from omnibot.client.events import Telemetry
from omnibot.errors import ConfigError
from omnibot.estimation.estimator import make_estimator
from omnibot.logs.run import Run
from omnibot.logs.topics import ADOPTED
from omnibot.motion import Estimate, Pose2D
from omnibot.protocol import text
from omnibot.protocol.messages import Telemetry as TelMessage
from omnibot.robot.description import RobotDescription


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
    return Replay(name, recorded, estimates, difference, note)


def _max_difference(live: list[tuple[float, float, float, float]], offline: list[Estimate]) -> float:
    """The largest of the position (m) and heading (rad) differences; inf if the counts differ."""
    if len(live) != len(offline):
        return math.inf
    worst = 0.0
    for (_, x, y, theta), e in zip(live, offline, strict=True):
        worst = max(worst, math.hypot(x - e.x, y - e.y), abs(theta - e.theta))
    return worst
