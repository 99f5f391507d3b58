"""Is a calibration better than none? Its own before/after accuracy check decides.

On every surface that was checked both ways, the mean absolute error of the check (MOVEs' distance
and ROTATEs' angle, as fractions of what was commanded) is compared with the one before calibrating:

* **each floor's own tables** (:func:`judge_floors`): if they are worse than none on their floor,
  the calibration is worse than none: ``omnibot calibrate`` neither uploads it nor writes it as if
  good (``--force`` writes it, marked), and exits 1 with the worst line;
* **the average over the floors** (:func:`judge_average`), checked on every floor: kept as the
  file's ``calibration`` (the tables for a robot that does not say which floor it is on) only when
  it is not worse than none on any of them; otherwise each floor keeps only its own tables.

The physics of the calibration is not judged here, only its result.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from omnibot.calibration.accuracy import AccuracyRow
from omnibot.calibration.results import CalibrationResult

Check = tuple[str, Sequence[AccuracyRow] | None, Sequence[AccuracyRow] | None]
"""(surface, the check's rows before calibrating, with the tables judged)."""


@dataclass(frozen=True)
class Verdict:
    """``better``: True, False, or None when there was no before/after check to decide with."""

    better: bool | None
    summary: str
    """One line: each surface's mean error before and after."""
    worst: str = ""
    """The check's line that got worst (course, speed: before -> after)."""
    hint: str = ""
    """When some floors' own tables are worse than none and others are not: what to do."""
    average: Verdict | None = None
    """The average over the floors (None: one floor, or no average)."""


def mean_abs_error(rows: Sequence[AccuracyRow]) -> float | None:
    """Mean absolute error of the rows that have one, None when none has."""
    errors = [abs(r.error) for r in rows if r.error is not None]
    return sum(errors) / len(errors) if errors else None


def _key(row: AccuracyRow) -> tuple[str, float, float, float]:
    return (row.kind, round(row.course_deg, 3), round(row.speed, 4), round(row.commanded, 4))


def _describe(row: AccuracyRow) -> str:
    if row.kind == "rotate":
        return f"ROTATE {row.commanded:+g} deg at {row.speed:g} deg/s"
    return f"MOVE course {row.course_deg:g} deg at {row.speed:g} m/s"


def worst_line(surface: str, before: Sequence[AccuracyRow], after: Sequence[AccuracyRow]) -> str:
    """The line of the check whose error grew the most."""
    old = {_key(r): r for r in before if r.error is not None}
    grown: list[tuple[float, str]] = []
    for row in after:
        was = old.get(_key(row))
        if row.error is None or was is None or was.error is None:
            continue
        growth = abs(row.error) - abs(was.error)
        grown.append(
            (
                growth,
                f"{surface}: {_describe(row)}: {100 * was.error:+.1f} % before, {100 * row.error:+.1f} % after",
            )
        )
    return max(grown)[1] if grown else ""


def judge(checks: Sequence[Check]) -> Verdict:
    """Better than none on every surface checked both ways (see the module docstring)?"""
    parts: list[str] = []
    worse: list[tuple[float, str]] = []
    better: list[str] = []
    for surface, before, after in checks:
        if before is None or after is None:
            continue
        b, a = mean_abs_error(before), mean_abs_error(after)
        if b is None or a is None:
            continue
        parts.append(f"{surface} {100 * b:.1f} % -> {100 * a:.1f} %")
        if a > b:
            worse.append((a - b, worst_line(surface, before, after)))
        else:
            better.append(surface)
    if not parts:
        return Verdict(None, "no before/after accuracy check to judge the calibration by")
    summary = "mean abs error of the accuracy check: " + ", ".join(parts)
    if worse:
        hint = ""
        if better:
            hint = (
                f"better than none on {', '.join(better)}: calibrate "
                + ("that floor" if len(better) == 1 else "those floors")
                + " alone (--surface NAME)"
            )
        return Verdict(False, summary, max(worse)[1], hint)
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
    return Verdict(own.better, own.summary, own.worst, own.hint, judge_average(result))
