"""A recorded run as plain tables: one pass over a log, the rows ``omnibot log`` reports, plots and
exports (poses, wheels, IMU, commands, protocol lines, link bytes, problems)."""

from __future__ import annotations

import itertools
import math
from collections import Counter, defaultdict
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from omnibot.config_errors import load_yaml
from omnibot.logs.reader import LogFile
from omnibot.logs.topics import (
    CALIBRATION,
    CMD_VEL,
    CONTROL,
    CYCLE,
    ESTIMATE,
    IMU,
    JOINT_STATES,
    LINK,
    ODOM,
    PROTOCOL,
    RANGE_PREFIX,
    ROBOT_DESCRIPTION,
    TRUTH,
    absolute,
)

PoseRow = tuple[float, float, float, float, float, float, float]
"""t, x, y, theta, vx, vy, w (pose in odom, twist in base_link)."""


def yaw_of(q: object) -> float:
    """The yaw (rad) of a quaternion about z."""
    z, w = float(getattr(q, "z", 0.0)), float(getattr(q, "w", 1.0))
    return 2.0 * math.atan2(z, w)


@dataclass
class Run:
    """Everything ``omnibot log`` needs from one log, times in s since the first message."""

    path: Path
    start_ns: int = 0
    end_ns: int = 0
    cut_short: str | None = None
    metadata: dict[str, dict[str, str]] = field(default_factory=dict)
    topics: dict[str, str] = field(default_factory=dict)
    """topic -> type name."""
    times: dict[str, list[float]] = field(default_factory=lambda: defaultdict(list))
    """topic -> the log times of its messages (s)."""
    estimate: list[PoseRow] = field(default_factory=list)
    estimate_exact: list[tuple[float, float, float, float]] = field(default_factory=list)
    """t, x, y, theta of ``/omnibot/estimate`` (theta unwrapped, as the estimator had it)."""
    truth: list[PoseRow] = field(default_factory=list)
    joints: list[tuple[float, list[str], list[float], list[float], list[float]]] = field(default_factory=list)
    """t, names, positions (rad), velocities (rad/s), efforts (PWM counts)."""
    imu: list[tuple[float, float, float]] = field(default_factory=list)
    """t, yaw rate (rad/s), yaw (rad)."""
    cmd_vel: list[tuple[float, float, float, float]] = field(default_factory=list)
    control: list[tuple[float, str, str, str]] = field(default_factory=list)
    """t, source in control, why, lock: the runtime's arbitration at each change."""
    ranges: dict[str, list[tuple[float, float]]] = field(default_factory=lambda: defaultdict(list))
    protocol: list[tuple[float, str, str, str]] = field(default_factory=list)
    """t, direction, keyword, text."""
    link: list[tuple[float, str, bytes, str]] = field(default_factory=list)
    """t, kind, data, note."""
    robot_description: str = ""
    calibration: str = ""
    cycles: list[tuple[float, Any]] = field(default_factory=list)
    """t, the decoded ``/omnibot/cycle`` message: each runtime cycle while a follower ran."""

    @property
    def duration(self) -> float:
        """Time from the first message to the last, s."""
        return max(0.0, (self.end_ns - self.start_ns) / 1e9)

    def problems(self) -> list[tuple[float, str, str]]:
        """(t, kind, text) of every warning, error reply or event, malformed message and link error."""
        out = [
            (t, kw if kw != "ERROR" else f"ERROR {d}", line)
            for t, d, kw, line in self.protocol
            if kw in ("WARN", "ERROR", "MALFORMED")
        ]
        out += [(t, "link", note) for t, kind, _, note in self.link if kind == "ERR"]
        return sorted(out)

    def omnibot_metadata(self) -> dict[str, str]:
        """The log's ``omnibot`` metadata (empty when it has none)."""
        return self.metadata.get("omnibot", {})

    def description(self) -> dict[str, object] | None:
        """The robot description recorded in the metadata, None when there is none; ConfigError when
        it is not YAML or gives a key twice."""
        text = self.omnibot_metadata().get("description")
        loaded = load_yaml(text, "robot description", f"{self.path} (omnibot metadata)") if text else None
        return loaded if isinstance(loaded, dict) else None


def _pose(t: float, msg: object) -> PoseRow:
    p = msg.pose.pose  # type: ignore[attr-defined]
    tw = msg.twist.twist  # type: ignore[attr-defined]
    return (
        t,
        float(p.position.x),
        float(p.position.y),
        yaw_of(p.orientation),
        float(tw.linear.x),
        float(tw.linear.y),
        float(tw.angular.z),
    )


def load_run(path: str | Path) -> Run:
    """Read the whole log at ``path`` into a :class:`Run` (a file cut short: up to its last chunk)."""
    log = LogFile.open(path)
    run = Run(log.path)
    first: int | None = None
    last = 0
    for m in log.messages():
        if first is None:
            first = m.ns
        last = max(last, m.ns)
        t = (m.ns - first) / 1e9
        topic = absolute(m.topic)
        run.topics.setdefault(topic, m.typename)
        run.times[topic].append(t)
        if topic not in _DECODED and not topic.startswith(RANGE_PREFIX):
            continue
        msg = m.decode()
        if topic == ODOM:
            run.estimate.append(_pose(t, msg))
        elif topic == CONTROL:
            run.control.append((t, str(msg.source), str(msg.reason), str(msg.lock)))
        elif topic == ESTIMATE:
            run.estimate_exact.append((t, float(msg.x), float(msg.y), float(msg.theta)))
        elif topic == TRUTH:
            run.truth.append(_pose(t, msg))
        elif topic == JOINT_STATES:
            run.joints.append(
                (
                    t,
                    list(msg.name),
                    [float(v) for v in msg.position],
                    [float(v) for v in msg.velocity],
                    [float(v) for v in msg.effort],
                )
            )
        elif topic == IMU:
            run.imu.append((t, float(msg.angular_velocity.z), yaw_of(msg.orientation)))
        elif topic == CMD_VEL:
            tw = msg.twist
            run.cmd_vel.append((t, float(tw.linear.x), float(tw.linear.y), float(tw.angular.z)))
        elif topic.startswith(RANGE_PREFIX):
            run.ranges[topic[len(RANGE_PREFIX) :]].append((t, float(msg.range)))
        elif topic == PROTOCOL:
            run.protocol.append((t, str(msg.direction), str(msg.keyword), str(msg.text)))
        elif topic == LINK:
            run.link.append((t, str(msg.kind), bytes(msg.data), str(msg.note)))
        elif topic == ROBOT_DESCRIPTION:
            run.robot_description = str(msg.data)
        elif topic == CALIBRATION:
            run.calibration = str(msg.data)
        elif topic == CYCLE:
            run.cycles.append((t, msg))
    run.start_ns, run.end_ns = first or 0, last
    run.cut_short = log.cut_short
    run.metadata = log.metadata
    return run


_DECODED = {
    CYCLE,
    CONTROL,
    ODOM,
    ESTIMATE,
    TRUTH,
    JOINT_STATES,
    IMU,
    CMD_VEL,
    PROTOCOL,
    LINK,
    ROBOT_DESCRIPTION,
    CALIBRATION,
}


def rate_and_gap(times: list[float]) -> tuple[float, float]:
    """(mean rate in Hz, longest gap in s) of a topic's message times."""
    if len(times) < 2:
        return 0.0, 0.0
    span = times[-1] - times[0]
    gap = max(b - a for a, b in itertools.pairwise(times))
    return ((len(times) - 1) / span if span > 0 else 0.0), gap


def keyword_counts(run: Run, direction: str) -> Counter[str]:
    """How often each keyword occurs among the protocol lines of one ``direction`` (``command``,
    ``reply`` or ``event``)."""
    return Counter(kw for _, d, kw, _ in run.protocol if d == direction)
