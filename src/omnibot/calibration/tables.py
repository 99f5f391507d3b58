"""Markdown tables of accuracy rows: course against speed, before and after (pure text)."""

from __future__ import annotations

from collections import defaultdict
from collections.abc import Sequence

from omnibot.calibration.accuracy import AccuracyRow, Summary, summarize


def _pct(v: float | None) -> str:
    return "-" if v is None else f"{100 * v:+.1f}"


def _deg(v: float | None) -> str:
    return "-" if v is None else f"{v:+.1f}"


def _fold_back(course: float) -> float:
    """A return course (c + 180) back to its outbound course."""
    c = course % 360.0
    return c - 180.0 if c >= 180.0 else c


def move_grid(rows: Sequence[AccuracyRow], field: str = "error") -> str:
    """Distance errors (%) or heading errors (degrees) of MOVEs: a line per course, a column per speed,
    each cell ``out / back`` (``*``: the controller warned that it had to reduce the speed, warning 11;
    ``!``: that the MOVE fell short on its wheel encoders, warning 17; ``^``: that it ran the MOVE at
    the calibrated reach, warning 18)."""
    moves = [r for r in rows if r.kind == "move"]
    speeds = sorted({r.speed for r in moves})
    cells: dict[tuple[float, float], list[str]] = defaultdict(list)
    fmt = _pct if field == "error" else _deg
    for r in moves:
        cells[(_fold_back(r.course_deg), r.speed)].append(
            fmt(getattr(r, field))
            + ("*" if r.saturated else "")
            + ("!" if r.short else "")
            + ("^" if r.clamped else "")
        )
    courses = sorted({c for c, _ in cells})
    unit = "distance error %" if field == "error" else field.removesuffix("_deg").replace("_", " ") + " deg"
    head = f"| course deg \\ speed m/s ({unit}, out / back) | " + " | ".join(f"{s:g}" for s in speeds) + " |"
    lines = [head, "|---|" + "---|" * len(speeds)]
    for c in courses:
        lines.append(f"| {c:g} | " + " | ".join(" / ".join(cells.get((c, s), ["-"])) for s in speeds) + " |")
    notes = []
    if any(r.saturated for r in moves):
        notes.append("\\* the controller warned: speed reduced (a motor could not get the power asked)")
    if any(r.short for r in moves):
        notes.append("! the controller warned: the MOVE fell short of its distance on the wheel encoders")
    if any(r.clamped for r in moves):
        notes.append(
            "^ the controller warned: run at the calibrated reach, slower than asked (distance kept)"
        )
    for note in notes:
        lines += ["", note]
    return "\n".join(lines)


def rotate_lines(rows: Sequence[AccuracyRow]) -> str:
    """The ROTATE rows as a Markdown table (commanded, rate, achieved, error); "" when there are none."""
    rot = [r for r in rows if r.kind == "rotate"]
    if not rot:
        return ""
    lines = ["| ROTATE deg | rate deg/s | achieved deg | error % |", "|---|---|---|---|"]
    for r in rot:
        got = "-" if r.achieved is None else f"{r.achieved:.1f}"
        lines.append(f"| {r.commanded:+g} | {r.speed:g} | {got} | {_pct(r.error)} |")
    return "\n".join(lines)


def summary_line(label: str, s: Summary) -> str:
    """One Markdown summary row: ``label``, then the mean and largest errors of ``s``."""

    def p(v: float | None) -> str:
        return "-" if v is None else f"{100 * v:.1f}"

    def d(v: float | None) -> str:
        return "-" if v is None else f"{v:.1f}"

    return (
        f"| {label} | {s.moves} | {p(s.distance_mean)} | {p(s.distance_max)} | {d(s.heading_mean_deg)} | "
        f"{d(s.heading_max_deg)} | {d(s.course_mean_deg)} | {d(s.course_max_deg)} | {p(s.rotate_mean)} | {p(s.rotate_max)} |"
    )


SUMMARY_HEAD = (
    "| calibration, surface | moves | distance mean abs % | max % | heading mean abs deg | max deg | "
    "course mean abs deg | max deg | ROTATE mean abs % | max % |\n|---|---|---|---|---|---|---|---|---|---|"
)


def summary_table(entries: Sequence[tuple[str, Sequence[AccuracyRow]]]) -> str:
    """The Markdown summary table of the accuracy checks, one row per ``(label, rows)`` entry."""
    return "\n".join([SUMMARY_HEAD, *(summary_line(label, summarize(rows)) for label, rows in entries)])
