"""Is a calibration better than none? Its own before/after accuracy check decides.

"Before" is the check run before calibrating, on the tables the robot was built with (its
description's ``calibration:``, the preset's in the simulator); "none" below means those. On every
surface that was checked both ways, the mean absolute error of the check (MOVEs' distance and
ROTATEs' angle, as fractions of what was commanded) is compared with the one before, over the whole
check and on each of its parts (:func:`part_of`: each course, both ways, and ROTATE), where a part
counts as worse when it grew by more than the check's own scatter (:func:`noise`):

* **each floor's own tables** (:func:`judge_floors`): if they are worse than none on their floor,
  over the whole check or on one of its parts, the calibration is worse than none: ``omnibot
  calibrate`` neither uploads it nor writes it as if good (``--force`` writes it, marked), and exits
  1 with the worst line and every part made worse;
* **the average over the floors** (:func:`judge_average`), checked on every floor: kept as the
  file's ``calibration`` (the tables for a robot that does not say which floor it is on) only when
  it is not worse than none on any of them, on the whole or on a part; otherwise each floor keeps only
  its own tables.

The physics of the calibration is not judged here, only its result.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace

from omnibot.calibration.accuracy import AccuracyRow
from omnibot.calibration.results import CalibrationResult

ROTATE = "ROTATE"
"""The check's ROTATEs, one part (:func:`part_of`)."""

Check = tuple[str, Sequence[AccuracyRow] | None, Sequence[AccuracyRow] | None]
"""(surface, the check's rows before calibrating, with the tables judged)."""

NOISE_MOVE = 0.03
"""A course counts as worse when its mean abs error (a fraction) grew by more than this, or than
:data:`NOISE_SHARE` of what it was when that is more: the check's own scatter. The same tables checked
again on the simulated robot (the wheels and their rollers starting where the check before left them)
moved a course's mean abs error by up to 2.3 % at about 2 % (mecanum4 on carpet, the diagonals), 1.0 %
at about 1 % (omni4 on carpet, courses 0 and 90) and 1.7 % at 54 % (mecanum4's preset on carpet)
(docs/calibration.md, *The verdict's margin*)."""
NOISE_ROTATE = 0.01
"""The same for ROTATE, whose mean abs error moved by up to 0.07 % (ten times that, rounded up)."""
NOISE_SHARE = 0.05


def noise(part: str, before: float) -> float:
    """How much a part's mean abs error ``before`` may grow before it counts as worse."""
    return max(NOISE_ROTATE if part == ROTATE else NOISE_MOVE, NOISE_SHARE * before)


@dataclass(frozen=True)
class Worse:
    """A part of the check (:func:`part_of`) whose mean abs error the tables made worse on a floor."""

    surface: str
    part: str
    before: float
    after: float
    line: str = ""
    """Its line whose error grew the most (what was commanded: before, after)."""

    def __str__(self) -> str:
        worst = f" (worst {self.line})" if self.line else ""
        return f"{self.surface}: {self.part}: {100 * self.before:.1f} % -> {100 * self.after:.1f} %{worst}"


@dataclass(frozen=True)
class Verdict:
    """``better``: True, False, or None when there was no before/after check to decide with."""

    better: bool | None
    summary: str
    """One line: each surface's mean error before and after."""
    worst: str = ""
    """When a floor's whole check got worse: its line that got worst (course, speed: before -> after)."""
    hint: str = ""
    """When some floors' own tables are worse than none and others are not: what to do."""
    average: Verdict | None = None
    """The average over the floors (None: one floor, or no average)."""
    worse: tuple[Worse, ...] = ()
    """Every part of the check (a course, ROTATE) made worse than before, on every floor."""

    @property
    def reason(self) -> str:
        """Why it is worse than none: :attr:`worst`, else the parts made worse ("" when it is not)."""
        return self.worst or "; ".join(str(w) for w in self.worse)

    @property
    def warning(self) -> str:
        """The line that marks a calibration its check found worse ("" when it did not)."""
        if self.better is not False:
            return ""
        return (
            f"WORSE THAN NO CALIBRATION: {self.worst}" if self.worst else f"WORSE THAN BEFORE: {self.reason}"
        )


def mean_abs_error(rows: Sequence[AccuracyRow]) -> float | None:
    """Mean absolute error of the rows that have one, None when none has."""
    errors = [abs(r.error) for r in rows if r.error is not None]
    return sum(errors) / len(errors) if errors else None


def part_of(row: AccuracyRow) -> str:
    """The part of the check a row belongs to: ``ROTATE``, or its course both ways (``course 90/270
    deg``: a MOVE and the one back)."""
    if row.kind == "rotate":
        return ROTATE
    course = round(row.course_deg % 180.0, 3)
    return f"course {course:g}/{course + 180.0:g} deg"


def part_errors(rows: Sequence[AccuracyRow]) -> dict[str, float]:
    """Mean abs error of each part of the check (:func:`part_of`), in the rows' order."""
    parts: dict[str, list[AccuracyRow]] = {}
    for row in rows:
        parts.setdefault(part_of(row), []).append(row)
    return {part: e for part, group in parts.items() if (e := mean_abs_error(group)) is not None}


def worse_parts(surface: str, before: Sequence[AccuracyRow], after: Sequence[AccuracyRow]) -> list[Worse]:
    """The parts of the check whose mean abs error grew by more than the check's :func:`noise`."""
    was, now = part_errors(before), part_errors(after)
    return [
        Worse(surface, p, was[p], e, _grown([r for r in before if part_of(r) == p], after))
        for p, e in now.items()
        if p in was and e > was[p] + noise(p, was[p])
    ]


def _key(row: AccuracyRow) -> tuple[str, float, float, float]:
    return (row.kind, round(row.course_deg, 3), round(row.speed, 4), round(row.commanded, 4))


def _describe(row: AccuracyRow) -> str:
    if row.kind == "rotate":
        return f"ROTATE {row.commanded:+g} deg at {row.speed:g} deg/s"
    return f"MOVE course {row.course_deg:g} deg at {row.speed:g} m/s"


def _grown(before: Sequence[AccuracyRow], after: Sequence[AccuracyRow]) -> str:
    """The line of the check whose error grew the most (what was commanded: before, after)."""
    old = {_key(r): r for r in before if r.error is not None}
    grown: list[tuple[float, str]] = []
    for row in after:
        was = old.get(_key(row))
        if row.error is None or was is None or was.error is None:
            continue
        line = f"{_describe(row)}: {100 * was.error:+.1f} % before, {100 * row.error:+.1f} % after"
        grown.append((abs(row.error) - abs(was.error), line))
    return max(grown, key=lambda g: g[0])[1] if grown else ""  # the first of equals


def worst_line(surface: str, before: Sequence[AccuracyRow], after: Sequence[AccuracyRow]) -> str:
    """The line of the check whose error grew the most, on ``surface``."""
    line = _grown(before, after)
    return f"{surface}: {line}" if line else ""


def judge(checks: Sequence[Check]) -> Verdict:
    """Better than none on every surface checked both ways (see the module docstring)?"""
    parts: list[str] = []
    worse: list[tuple[float, str]] = []
    worse_part: list[Worse] = []
    better: list[str] = []
    for surface, before, after in checks:
        if before is None or after is None:
            continue
        b, a = mean_abs_error(before), mean_abs_error(after)
        if b is None or a is None:
            continue
        parts.append(f"{surface} {100 * b:.1f} % -> {100 * a:.1f} %")
        grown = worse_parts(surface, before, after)
        worse_part += grown
        if a > b:
            worse.append((a - b, worst_line(surface, before, after)))
        elif not grown:
            better.append(surface)
    if not parts:
        return Verdict(None, "no before/after accuracy check to judge the calibration by")
    summary = "mean abs error of the accuracy check: " + ", ".join(parts)
    if worse or worse_part:
        hint = ""
        if better:
            hint = (
                f"better than none on {', '.join(better)}: calibrate "
                + ("that floor" if len(better) == 1 else "those floors")
                + " alone (--surface NAME)"
            )
        return Verdict(False, summary, max(worse)[1] if worse else "", hint, worse=tuple(worse_part))
    return Verdict(True, summary)


def judge_floors(result: CalibrationResult) -> Verdict:
    """Each floor's own tables against none, on that floor."""
    return judge([(s.surface, s.before, s.after) for s in result.sessions])


def judge_average(result: CalibrationResult) -> Verdict | None:
    """The average over the floors against none, on every floor (None: no average)."""
    if result.average is None:
        return None
    return judge([(s.surface, s.before, result.average_checks.get(s.surface)) for s in result.sessions])


def judge_calibration(result: CalibrationResult) -> Verdict:
    """The verdict on ``result``: each floor's own tables decide, the average's verdict attached."""
    own = judge_floors(result)
    return replace(own, average=judge_average(result))
