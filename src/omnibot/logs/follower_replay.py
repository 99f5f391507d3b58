"""Re-run a path follower offline on a recorded run: the live one, to check that the log holds all it
needs (its commands are reproduced exactly), or another follower or other options, to see what it
would have commanded.

A run recorded on the runtime while a follower drove (``omnibot follow``, ``run --follow``, the
dashboard's repeat; see :class:`omnibot.logs.sink.FollowerLog`) holds each cycle the follower
source was asked (``/omnibot/cycle``: the clocks, the estimate it was handed, the decision after it)
and, per follower run, the follower's registered name, options, limits, path and start time (MCAP
metadata ``omnibot_follower/RUN``). :func:`replay_follower` rebuilds the follower source with them
(or with another follower, other options) and hands it the recorded cycles one by one, as the
runtime did: the same estimate, clocks, previous decision, latched stop and error notices.

Open loop: the states are those of the live run. A follower other than the live one is shown what
the robot did under the live commands, not under its own: its commands say what it would have asked
for at each of those states, and the robot did not respond to them.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np

from omnibot.control import Follower, MotionLimits, Path, make_follower
from omnibot.errors import ConfigError
from omnibot.logs.run import Run
from omnibot.logs.topics import FOLLOWER
from omnibot.motion import Estimate, Twist
from omnibot.runtime import NOBODY, Cycle, Decision, FollowerSource, Notice


@dataclass(frozen=True)
class RecordedFollower:
    """One follower run of a log: how to rebuild it, and its cycles (t, decoded Cycle message)."""

    run: int
    source: str
    follower: str
    options: dict[str, Any]
    limits: MotionLimits
    path: Path
    t0: float
    on_override: str
    cycles: list[tuple[float, Any]]


@dataclass(frozen=True)
class CommandRow:
    """One recorded cycle: its log time (s), who was in control, the twist the live follower
    commanded (None: it did not drive this cycle) and the replayed follower's (None: silent)."""

    t: float
    source: str
    live: Twist | None
    replayed: Twist | None


@dataclass(frozen=True)
class FollowerReplay:
    """The follower re-run on a run's cycles, and how its commands compare with the live ones."""

    recorded: RecordedFollower
    follower: str
    options: dict[str, Any]
    rows: list[CommandRow]
    compared: int
    """Cycles the live follower drove (its command against the replayed one)."""
    max_difference: float
    """Largest difference of vx, vy (m/s) or w (rad/s) over the compared cycles; inf when the replay
    was silent where the live follower drove; 0.0: the live commands exactly."""
    rms: tuple[float, float, float]
    """RMS differences of vx, vy (m/s) and w (rad/s) over the compared cycles where both spoke."""
    finished_at: float | None
    """Log time (s) of the cycle after which the replayed follower fell silent (None: it never did)."""

    @property
    def is_live(self) -> bool:
        """The follower and options replayed are the live ones."""
        return self.follower == self.recorded.follower and self.options == self.recorded.options

    @property
    def reproduced(self) -> bool:
        """The live follower's commands, every one, exactly."""
        return self.compared > 0 and self.max_difference == 0.0


def recorded_followers(run: Run) -> list[RecordedFollower]:
    """The follower runs of a log, in order (empty: none was recorded)."""
    out = []
    for name, meta in sorted(run.metadata.items()):
        if not name.startswith(f"{FOLLOWER}/"):
            continue
        number = int(name.rsplit("/", 1)[1])
        columns = json.loads(meta["path"])
        path = Path(**{k: np.asarray(v, dtype=float) for k, v in columns.items() if v is not None})
        out.append(
            RecordedFollower(
                run=number,
                source=meta["source"],
                follower=meta["follower"],
                options=json.loads(meta["options"]),
                limits=MotionLimits(**json.loads(meta["limits"])),
                path=path,
                t0=float(meta["t0"]),
                on_override=meta.get("on_override", "resume"),
                cycles=[(t, c) for t, c in run.cycles if int(c.run) == number],
            )
        )
    return sorted(out, key=lambda r: r.run)


def parse_options(items: list[str] | None) -> dict[str, Any]:
    """``--follower-option KEY=VALUE`` items as options (each value read as YAML: ``45``, ``true``,
    ``[4, 0.5, 0.1]``); ConfigError for an item without ``=``."""
    from omnibot.config_errors import load_yaml

    out: dict[str, Any] = {}
    for item in items or []:
        key, sep, value = item.partition("=")
        if not sep or not key.strip():
            raise ConfigError(f"expected KEY=VALUE, got {item!r}", key="--follower-option")
        try:
            parsed = load_yaml(value)
        except ConfigError:
            parsed = None
        if not _option_value(parsed):
            raise ConfigError(
                f"expected KEY=NUMBER, true/false or a list of numbers, got {item!r}", key="--follower-option"
            )
        out[key.strip()] = parsed
    return out


def _option_value(value: object) -> bool:
    """A follower option's value: a finite number, a bool, or a list of finite numbers."""
    if isinstance(value, bool):
        return True
    if isinstance(value, int | float):
        return math.isfinite(value)
    return (
        isinstance(value, list)
        and bool(value)
        and all(_option_value(v) and not isinstance(v, list) for v in value)
    )


def make_replayed(
    recorded: RecordedFollower, follower: str | None = None, options: dict[str, Any] | None = None
) -> tuple[str, dict[str, Any], Follower]:
    """The follower to replay: ``follower`` (default the live one) with the live options (another
    follower: only the live rate) updated by ``options``; ConfigError for an unknown follower or
    option, or a value it refuses."""
    name = follower or recorded.follower
    opts = dict(recorded.options) if name == recorded.follower else {"rate": recorded.options.get("rate")}
    opts = {k: v for k, v in {**opts, **(options or {})}.items() if v is not None}
    try:
        return name, opts, make_follower(name, recorded.limits, **opts)
    except (TypeError, ValueError) as exc:
        text = str(exc)
        unknown = text.partition("has no option(s) ")[2]
        if unknown:
            raise ConfigError(f"follower {name!r} has no option {unknown}", key="--follower-option") from None
        if "unknown follower" in text:
            raise ConfigError(text, key="--follower") from None
        raise ConfigError(f"{name}: {text}", key="--follower-option" if options else "--follower") from None


def replay_follower(
    recorded: RecordedFollower, follower: str | None = None, options: dict[str, Any] | None = None
) -> FollowerReplay:
    """Run ``follower`` (default: the live one, see :func:`make_replayed`) over the recorded cycles."""
    name, opts, made = make_replayed(recorded, follower, options)
    on_override: Literal["resume", "stop"] = "stop" if recorded.on_override == "stop" else "resume"
    source = FollowerSource(made, recorded.path, name=recorded.source, on_override=on_override)
    previous = NOBODY
    rows: list[CommandRow] = []
    finished_at: float | None = None
    for t, c in recorded.cycles:
        estimate = _estimate(c)
        if not source.started and estimate is not None:
            source.start(recorded.t0)
        cycle = Cycle(int(c.index), float(c.now), float(c.t), estimate, decision=previous)
        cycle.latched = bool(c.latched)
        cycle.notices = [Notice("error", str(text), recorded.source) for text in c.errors]
        was_finished = source.finished
        try:
            proposal = source.propose(cycle)
        except (TypeError, ValueError, ArithmeticError, IndexError) as exc:
            raise ConfigError(
                f"{name} with {opts} failed at t={t:.3f} s of the log: {exc}", key="--follower-option"
            ) from None
        if source.finished and not was_finished:
            finished_at = t
        decided = _twist(c.twist) if c.has_twist else None
        live = decided if str(c.source) == recorded.source else None
        rows.append(CommandRow(t, str(c.source), live, proposal.twist if proposal else None))
        previous = Decision(str(c.source), decided, "", lock=str(c.lock), estop=bool(c.estop))
    return _compare(recorded, name, opts, rows, finished_at)


def _estimate(c: Any) -> Estimate | None:
    if not c.has_estimate:
        return None
    return Estimate(
        float(c.estimate_t),
        float(c.x),
        float(c.y),
        float(c.theta),
        float(c.vx),
        float(c.vy),
        float(c.w),
        bool(c.slipping),
        bool(c.standstill),
    )


def _twist(msg: Any) -> Twist:
    return Twist(float(msg.linear.x), float(msg.linear.y), float(msg.angular.z))


def _compare(
    recorded: RecordedFollower,
    name: str,
    options: dict[str, Any],
    rows: list[CommandRow],
    finished_at: float | None,
) -> FollowerReplay:
    compared = [r for r in rows if r.live is not None]
    both = [(r.live, r.replayed) for r in compared if r.live is not None and r.replayed is not None]
    worst = math.inf if len(both) < len(compared) else 0.0
    for live, replayed in both:
        worst = max(worst, abs(live.vx - replayed.vx), abs(live.vy - replayed.vy), abs(live.w - replayed.w))
    if both:
        diff = np.array([(a.vx - b.vx, a.vy - b.vy, a.w - b.w) for a, b in both])
        rx, ry, rw = (float(v) for v in np.sqrt(np.mean(diff**2, axis=0)))
    else:
        rx = ry = rw = math.nan
    return FollowerReplay(recorded, name, options, rows, len(compared), worst, (rx, ry, rw), finished_at)
