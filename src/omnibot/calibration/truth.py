"""Ground truth for calibration runs: what the robot really did, by one of several strategies.

Each strategy is a small class registered under its ``--truth`` name (DESIGN habit 6):

==========  ===================================================================================
sim         the simulator's own pose (a ``sim://`` link or any in-process SimDevice link)
csv:FILE    the emulator's ``--truth`` CSV (``omnibot sim --pty --truth FILE``), last row
encoders    wheel odometry on the controller's TEL encoder counts (a real robot with encoders);
            ``encoders:CAL.yaml`` with the wheel radius and base corrections of that file
sonar       a sonar facing a wall: range before and after a straight run (no rotations)
tape        a person measures each run and types the result at a prompt
==========  ===================================================================================

A strategy takes a :meth:`~TruthSource.mark` before a run and turns it into a
:class:`~omnibot.calibration.runs.Motion` after it (the robot stopped): the displacement in the body
frame at the run's start, and the angle turned, each None where the strategy cannot tell. :class:`TruthChain` asks the first strategy that
can measure a run (``sonar`` falls back to ``encoders`` for rotations).
"""

from __future__ import annotations

import csv
import difflib
import math
import statistics
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from omnibot.calibration.calfile import load_calibration
from omnibot.calibration.runs import ROTATE, SQUARE, STRAIGHT, TURN, Motion, RunInfo, relative
from omnibot.calibration.tap import TelemetryTap
from omnibot.calibration.umbmark import corrected_robot
from omnibot.client import RobotClient
from omnibot.errors import ConfigError
from omnibot.estimation import WheelOdometry
from omnibot.motion import Pose2D
from omnibot.robot import RobotDescription

Ask = Callable[[str], str]
"""A prompt function (``input`` by default; tests pass a fake person)."""


class TruthSource:
    """Base of the strategies: ``mark()`` before a run, ``measure(mark, run)`` after it."""

    name: str = ""
    kinds: frozenset[str] = frozenset({STRAIGHT, ROTATE, TURN, SQUARE})
    exact: bool = True
    """True when the source is independent of the robot's own sensors (sim, csv, tape)."""
    live: bool = False
    """True when it can also measure while the robot moves (the simulator)."""

    def can(self, run: RunInfo) -> bool:
        """Whether this source can measure ``run`` (by its kind)."""
        return run.kind in self.kinds

    def mark(self) -> Any:
        """Take what :meth:`measure` needs before a run (None by default)."""
        return None

    def measure(self, mark: Any, run: RunInfo) -> Motion | None:
        """The motion since ``mark`` for ``run``, None when it could not be measured."""
        raise NotImplementedError

    def describe(self) -> str:
        """The source as the ``--truth`` option names it."""
        return self.name


@dataclass
class TruthContext:
    """What a strategy may use: the client, the robot, the telemetry tap and a prompt."""

    client: RobotClient
    robot: RobotDescription
    tap: TelemetryTap
    ask: Ask = input


TruthFactory = Callable[[TruthContext, str], TruthSource]
TRUTHS: dict[str, TruthFactory] = {}


def register_truth(name: str) -> Callable[[TruthFactory], TruthFactory]:
    """Register a truth strategy factory under ``name`` (what ``--truth`` accepts)."""

    def deco(factory: TruthFactory) -> TruthFactory:
        TRUTHS[name] = factory
        return factory

    return deco


# --------------------------------------------------------------------------- strategies


class SimTruth(TruthSource):
    """The simulator's ground-truth pose (in-process links only)."""

    name = "sim"
    live = True

    def __init__(self, sim: Any) -> None:
        self.sim = sim

    def mark(self) -> tuple[float, float, float]:
        """The simulator's true pose now ``(x, y, theta)``."""
        p = self.sim.pose
        return (p.x, p.y, p.theta)

    def measure(self, mark: Any, run: RunInfo) -> Motion:
        """The simulator's true motion since ``mark``."""
        p = self.sim.pose
        x0, y0, th0 = mark
        return relative(x0, y0, th0, p.x, p.y, p.theta, "sim")


def simulator_of(client: RobotClient) -> Any:
    """The Simulator behind an in-process link, or None."""
    from omnibot.transport import find_simulator

    return find_simulator(client.link)


@register_truth("sim")
def _sim(ctx: TruthContext, arg: str) -> TruthSource:
    sim = simulator_of(ctx.client)
    if sim is None:
        raise ConfigError(
            f"truth 'sim' needs an in-process simulator link (sim://...), not {ctx.client.link.url}",
            key="--truth",
        )
    return SimTruth(sim)


class CsvTruth(TruthSource):
    """The last row (t, x, y, theta) of the emulator's ground-truth CSV (flushed every 100 ms)."""

    name = "csv"
    FLUSH = 0.15

    def __init__(self, client: RobotClient, path: Path) -> None:
        self.client = client
        self.path = path

    def _last(self) -> tuple[float, float, float]:
        self.client.sleep(self.FLUSH)
        try:
            with self.path.open(newline="") as f:
                rows = [r for r in csv.DictReader(f) if r.get("theta")]
            last = rows[-1]
            return (float(last["x"]), float(last["y"]), float(last["theta"]))
        except (OSError, ValueError, KeyError, IndexError) as exc:
            raise ConfigError(
                f"cannot read a pose from truth file {self.path}: {exc}", key="--truth"
            ) from None

    def mark(self) -> tuple[float, float, float]:
        """The file's latest pose ``(x, y, theta)``."""
        return self._last()

    def measure(self, mark: Any, run: RunInfo) -> Motion:
        """The motion between ``mark`` and the file's latest pose."""
        (x0, y0, th0), (x1, y1, th1) = mark, self._last()
        return relative(x0, y0, th0, x1, y1, th1, "csv")

    def describe(self) -> str:
        """``csv:`` and the file's path."""
        return f"csv:{self.path}"


@register_truth("csv")
def _csv(ctx: TruthContext, arg: str) -> TruthSource:
    if not arg:
        raise ConfigError("truth 'csv' needs a file: --truth csv:truth.csv", key="--truth")
    return CsvTruth(ctx.client, Path(arg))


class EncoderTruth(TruthSource):
    """Wheel odometry from the controller's encoder counts (what a real robot knows of itself).

    With ``odometry`` (a WheelOdometry fed by the tap with corrected geometry, see ``encoders:FILE``)
    it measures with the wheel radius and base of an earlier calibration.
    """

    name = "encoders"
    exact = False

    def __init__(self, tap: TelemetryTap, odometry: WheelOdometry | None = None) -> None:
        self.tap = tap
        self.odometry = odometry

    def _pose(self) -> Pose2D | None:
        return self.odometry.pose if self.odometry is not None else self.tap.odometry_pose

    def mark(self) -> Any:
        """The encoder odometry's pose now (None before the first telemetry)."""
        return self._pose()

    def measure(self, mark: Any, run: RunInfo) -> Motion | None:
        """The odometry's motion since ``mark``, None when either pose is unknown."""
        end = self._pose()
        if mark is None or end is None:
            return None
        return relative(mark.x, mark.y, mark.theta, end.x, end.y, end.theta, "encoders")


@register_truth("encoders")
def _encoders(ctx: TruthContext, arg: str) -> TruthSource:
    """``encoders``, or ``encoders:CAL.yaml`` to use that file's odometry corrections."""
    if not ctx.robot.has_wheel_encoders:
        raise ConfigError(
            f"truth 'encoders' needs an encoder on every wheel; {ctx.robot.name} has encoders on "
            f"{[e.wheel for e in ctx.robot.encoders.motors] or 'none'}",
            key="--truth",
        )
    if not arg:
        return EncoderTruth(ctx.tap)
    cal = load_calibration(arg)
    cal.check_robot(ctx.robot.name, arg)
    odo = cal.odometry or {}
    try:
        radius, base = float(odo["wheel_radius_scale"]), float(odo["wheel_base_scale"])
    except (KeyError, TypeError, ValueError):
        raise ConfigError(
            f"{arg} has no odometry wheel_radius_scale and wheel_base_scale", key="--truth"
        ) from None
    return EncoderTruth(ctx.tap, ctx.tap.add_odometry(corrected_robot(ctx.robot, radius, base)))


class SonarTruth(TruthSource):
    """A sonar facing a wall: the median range over a short standstill before and after a straight run.

    The range change is the travel along the sonar's axis; divided by cos(course - sonar angle) it
    is the distance along the course (assuming the robot kept its commanded course). Runs whose
    course is more than 60 degrees off the sonar's axis cannot be measured.
    """

    name = "sonar"
    kinds = frozenset({STRAIGHT})
    exact = False
    WINDOW = 0.4

    def __init__(self, ctx: TruthContext, index: int) -> None:
        self.ctx = ctx
        self.index = index
        self.angle = ctx.robot.sonars[index].angle
        period = max(0.06, ctx.robot.sonars[index].period_min)
        ctx.client.sonar(index + 1, period)

    def can(self, run: RunInfo) -> bool:
        """Only straight runs within 60 degrees of the sonar's axis (it measures the range's change)."""
        return (
            run.kind == STRAIGHT and run.course is not None and abs(math.cos(run.course - self.angle)) >= 0.5
        )

    def _range(self) -> float | None:
        values = [
            r[self.index]
            for tel in self.ctx.tap.collect(self.WINDOW)
            if (r := tel.ranges) is not None and len(r) > self.index and r[self.index] is not None
        ]
        return statistics.median(v for v in values if v is not None) if values else None

    def mark(self) -> float | None:
        """The sonar's range now, m: the median of the last window's readings (None without one)."""
        return self._range()

    def measure(self, mark: Any, run: RunInfo) -> Motion | None:
        """The distance along the course from the change of range, None when either range is missing."""
        after = self._range()
        if mark is None or after is None or run.course is None:
            return None
        return Motion(along=(mark - after) / math.cos(run.course - self.angle), source="sonar")


@register_truth("sonar")
def _sonar(ctx: TruthContext, arg: str) -> TruthSource:
    sonars = ctx.robot.sonars
    if not sonars:
        raise ConfigError(f"truth 'sonar' needs a sonar; {ctx.robot.name} has none", key="--truth")
    names = [s.name for s in sonars]
    if not arg:
        return SonarTruth(ctx, 0)
    if arg in names:
        return SonarTruth(ctx, names.index(arg))
    close = difflib.get_close_matches(arg, names, n=1)
    hint = f"; did you mean '{close[0]}'?" if close else f"; expected one of: {', '.join(names)}"
    raise ConfigError(f"no sonar '{arg}'{hint}", key="--truth")


class TapeTruth(TruthSource):
    """A person with a tape measure and a protractor answers a prompt after every run.

    Straight runs ask the distance in cm (along the course); rotations and turns the angle turned
    in degrees (counter-clockwise positive); a square the end position ``x,y`` in cm in the start
    frame (x forward, y left) and the heading change in degrees. An empty answer skips the run.
    """

    name = "tape"

    def __init__(self, ask: Ask) -> None:
        self.ask = ask

    def _numbers(self, prompt: str, count: int) -> list[float] | None:
        while True:
            text = self.ask(prompt).strip()
            if not text:
                return None
            try:
                values = [float(v) for v in text.replace(";", ",").split(",")]
            except ValueError:
                values = []
            if len(values) == count and all(math.isfinite(v) for v in values):
                return values
            prompt = f"  please type {count} number(s) separated by commas (or nothing to skip): "

    def measure(self, mark: Any, run: RunInfo) -> Motion | None:
        """Ask the person what the tape measured (distance, angle, or end point and heading change); None
        when they give nothing."""
        if run.kind == STRAIGHT:
            got = self._numbers(f"{run.text}: distance travelled [cm]? ", 1)
            return None if got is None else Motion(along=got[0] / 100.0, source="tape")
        if run.kind in (ROTATE, TURN):
            got = self._numbers(f"{run.text}: angle turned [deg, ccw +]? ", 1)
            return None if got is None else Motion(theta=math.radians(got[0]), source="tape")
        got = self._numbers(f"{run.text}: end x,y [cm] and heading change [deg]? ", 3)
        if got is None:
            return None
        return Motion(x=got[0] / 100.0, y=got[1] / 100.0, theta=math.radians(got[2]), source="tape")


@register_truth("tape")
def _tape(ctx: TruthContext, arg: str) -> TruthSource:
    return TapeTruth(ctx.ask)


# --------------------------------------------------------------------------- chain and factory


class TruthChain(TruthSource):
    """The first of several strategies that can measure a run measures it."""

    def __init__(self, sources: list[TruthSource]) -> None:
        self.sources = sources
        self.name = sources[0].name
        self.exact = sources[0].exact

    def can(self, run: RunInfo) -> bool:
        """Whether any source of the chain can measure ``run``."""
        return any(s.can(run) for s in self.sources)

    def mark(self) -> list[Any]:
        """Every source's mark, in order."""
        return [s.mark() for s in self.sources]

    def measure(self, mark: Any, run: RunInfo) -> Motion | None:
        """The measurement of the first source that can measure ``run``."""
        for source, m in zip(self.sources, mark, strict=True):
            if source.can(run):
                return source.measure(m, run)
        return None

    def describe(self) -> str:
        """The sources' names joined by "then"."""
        return " then ".join(s.describe() for s in self.sources)


def parse_truth_spec(spec: str) -> tuple[str, str]:
    """``name`` or ``name:argument`` -> (name, argument), the name checked against the registry."""
    name, _, arg = spec.partition(":")
    name = name.strip().lower()
    if name not in TRUTHS:
        close = difflib.get_close_matches(name, list(TRUTHS), n=1)
        hint = f"; did you mean '{close[0]}'?" if close else ""
        raise ConfigError(
            f"unknown truth strategy '{spec}'{hint}; expected one of: {', '.join(sorted(TRUTHS))}",
            key="--truth",
        )
    return name, arg.strip()


def make_truth(spec: str, ctx: TruthContext) -> TruthSource:
    """The strategy named by ``spec``; strategies that cannot measure rotations fall back to encoders."""
    name, arg = parse_truth_spec(spec)
    primary = TRUTHS[name](ctx, arg)
    if primary.kinds != TruthSource.kinds and name != "encoders" and ctx.robot.has_wheel_encoders:
        return TruthChain([primary, EncoderTruth(ctx.tap)])
    return primary


def default_truth(client: RobotClient, robot: RobotDescription) -> str:
    """``sim`` on an in-process simulator, else ``encoders`` if every wheel has one, else ``tape``."""
    if simulator_of(client) is not None:
        return "sim"
    return "encoders" if robot.has_wheel_encoders else "tape"
