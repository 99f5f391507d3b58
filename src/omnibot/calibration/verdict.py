"""Is a calibration better than none? Its own before/after accuracy check decides.

On every surface that was checked both ways, the mean absolute error of the check (MOVEs' distance
and ROTATEs' angle, as fractions of what was commanded) with the calibration that would be kept (the
average over the surfaces, else the surface's own) is compared with the one before calibrating. If
it is larger on any surface, the calibration is worse than none: ``omnibot calibrate`` neither
uploads it nor writes it as if good (``--force`` writes it, marked), and exits 1 with the worst
line. The physics of the calibration is not judged here, only its result.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from omnibot.calibration.accuracy import AccuracyRow
from omnibot.calibration.results import CalibrationResult


@dataclass(frozen=True)
class Verdict:
    """``better``: True, False, or None when there was no before/after check to decide with."""

    better: bool | None
    summary: str
    """One line: each surface's mean error before and after."""
    worst: str = ""
    """The check's line that got worst (course, speed: before -> after)."""
    hint: str = ""
    """When the average over the floors is refused: how each floor's own tables did."""


def mean_abs_error(rows: Sequence[AccuracyRow]) -> float | None:
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


def judge_calibration(result: CalibrationResult) -> Verdict:
    """The verdict of ``result``'s own accuracy checks (see the module docstring)."""
    parts: list[str] = []
    worse: list[tuple[float, str]] = []
    checked = False
    for session in result.sessions:
        after = result.average_checks.get(session.surface) if result.average is not None else session.after
        if session.before is None or after is None:
            continue
        b, a = mean_abs_error(session.before), mean_abs_error(after)
        if b is None or a is None:
            continue
        checked = True
        parts.append(f"{session.surface} {100 * b:.1f} % -> {100 * a:.1f} %")
        if a > b:
            worse.append((a - b, worst_line(session.surface, session.before, after)))
    if not checked:
        return Verdict(None, "no before/after accuracy check to judge the calibration by")
    summary = "mean abs error of the accuracy check: " + ", ".join(parts)
    if worse:
        return Verdict(False, summary, max(worse)[1], _own_tables(result))
    return Verdict(True, summary)


def _own_tables(result: CalibrationResult) -> str:
    """Each floor's own tables against none, when the refused calibration is the average."""
    if result.average is None:
        return ""
    own = []
    for session in result.sessions:
        b = mean_abs_error(session.before) if session.before else None
        a = mean_abs_error(session.after) if session.after else None
        if a is not None and b is not None:
            own.append(f"{session.surface} {100 * b:.1f} % -> {100 * a:.1f} %")
    if not own:
        return ""
    return (
        "each floor's own tables: " + ", ".join(own) + " (calibrate one floor at a time with --surface NAME)"
    )
