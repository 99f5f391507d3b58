"""The report directory of ``omnibot calibrate``: seed 000's figures 5-7, accuracy tables and raw data.

=====================  ===========================================================================
fig5_rates.png         rate (cm/s of the busiest wheel's rim) against power: each course, rotation
fig6_kt_kr.png         K_t and K_r against power, per surface and averaged (K_r also in seed 000's terms)
fig7_kl.png            K_l against power for each calibrated course
accuracy.png           MOVE distance error against course, before and after
accuracy.md            the before/after tables (markdown)
accuracy.json          every accuracy row and the summaries
runs.json              every run: command, truth, odometry, gyro
=====================  ===========================================================================
"""

from __future__ import annotations

import json
import math
import statistics
from collections.abc import Sequence
from dataclasses import asdict
from pathlib import Path
from typing import Any

from omnibot.calibration.accuracy import AccuracyRow, describe_reach, reach_speed, summarize
from omnibot.calibration.calfile import describe_spec
from omnibot.calibration.results import CalibrationResult, SurfaceSession
from omnibot.calibration.seedterms import seed_kr
from omnibot.calibration.tables import move_grid, rotate_lines, summary_table
from omnibot.errors import ConfigError
from omnibot.navigation import SlipCalibration
from omnibot.robot import CalibrationSpec, PiecewiseLinear

STYLES = ("-", "--", ":", "-.")


def accuracy_entries(result: CalibrationResult) -> list[tuple[str, list[AccuracyRow]]]:
    """(label, rows) of every accuracy check, in the report's order."""
    out: list[tuple[str, list[AccuracyRow]]] = []
    for s in result.sessions:
        if s.before is not None:
            out.append((f"before, {s.surface}", s.before))
        if s.after is not None:
            out.append((f"after ({s.surface} calibration), {s.surface}", s.after))
    for surface, rows in result.average_checks.items():
        out.append((f"after (average calibration), {surface}", rows))
    return out


def accuracy_markdown(result: CalibrationResult) -> str:
    """The accuracy report as Markdown: each check's summary and its MOVE and ROTATE tables."""
    entries = accuracy_entries(result)
    lines = [
        f"# Calibration accuracy: {result.robot.name}",
        "",
        "Open-loop MOVEs of the same length on each course and speed, each followed by one back on the",
        "course + 180 degrees, and ROTATEs both ways; achieved distance against commanded (truth: "
        f"{result.sessions[0].truth if result.sessions else '-'}).",
        "",
        "## Summary",
        "",
        summary_table(entries) if entries else "(no accuracy checks were run)",
    ]
    if result.average is not None and result.average_better is not None:
        lines += [
            "",
            "The average over the floors is "
            + (
                "better than no calibration on every floor: the file's `calibration`."
                if result.average_better
                else "worse than no calibration on a floor: not kept; each floor keeps its own tables "
                "(`surfaces.<floor>.calibration`, uploaded where the robot stands)."
            ),
        ]
    if result.sessions:
        lines += ["", *reach_lines(result)]
    lines += _roller_lines(result)
    for label, rows in entries:
        lines += ["", f"## {label}", "", move_grid(rows), "", move_grid(rows, "heading_error_deg"), ""]
        lines += [move_grid(rows, "course_error_deg"), "", rotate_lines(rows)]
    lines += _slip_lines(result)
    notes = [f"- {s.surface}: {n}" for s in result.sessions for n in s.notes]
    if notes:
        lines += ["", "## Notes", "", *notes]
    return "\n".join(lines) + "\n"


def _roller_lines(result: CalibrationResult) -> list[str]:
    """The roller drag section: each surface's drag fit and coast table (none without a fit)."""
    drags = [(s.surface, s.fit.rollers, s.fit.coast) for s in result.sessions if s.fit.rollers is not None]
    if not drags:
        return []
    lines = [
        "",
        "## Roller drag (wheels standing still on a motor axis)",
        "",
        "Each wheel's drag amplitude (PWM counts, over its roller phase; the slowest coast MOVEs' where",
        "they measured it, else the drag runs'), the drag runs' rms distance scatter without and with",
        "the term (kept: uploaded), and the coast table the MOVEs gave (s the drag outlasts a MOVE, at",
        "its speed; the drag runs' own where there were no MOVEs).",
        "",
        "| surface | amplitude per wheel | runs | rms before / after, mm | kept | coast s at m/s |",
        "|---|---|---|---|---|---|",
    ]
    for surface, fit, tuned in drags:
        cos, sin = (tuned.cos, tuned.sin) if tuned and tuned.cos and tuned.sin else (fit.cos, fit.sin)
        amps = ", ".join(f"{math.hypot(c, s):.1f}" for c, s in zip(cos, sin, strict=True))
        pts = (
            zip(tuned.table.x, tuned.table.y, strict=True)
            if tuned
            else zip(fit.speeds, fit.coast, strict=True)
        )
        coast = ", ".join(f"{k:.2f} at {v:.2f}" for v, k in pts if v > 0)
        lines.append(
            f"| {surface} | {amps} | {fit.runs} | {1000 * fit.rms_before:.1f} / {1000 * fit.rms_after:.1f} | "
            f"{'yes' if fit.kept else 'no'} | {coast} |"
        )
    return lines


def _slip_lines(result: CalibrationResult) -> list[str]:
    """The wheel slip section: each surface's fitted creep and its errors (none without a fit)."""
    slips = [(s.surface, s.slip) for s in result.sessions if s.slip is not None]
    if not slips:
        return []
    lines = [
        "",
        "## Wheel slip (driven-wheel odometry)",
        "",
        "Straight runs out and back on evenly spaced courses with the wheel-speed loop on; the encoders'",
        "displacement against the truth's, raw and with the fitted creep taken out",
        "(`surfaces.<floor>.odometry.slip`, for `omnibot follow --calibration`).",
        "",
        "| surface | roll (m/s) | combined | compliance (s) | ramp (s^3/m) | scale | runs | raw error, mean / max "
        "| corrected, mean / max |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for surface, slip in slips:
        raw, fixed = slip.errors(corrected=False), slip.errors(corrected=True)
        lines.append(
            f"| {surface} | {slip.params.roll:.4f} | {slip.params.combined:.4f} | {slip.params.compliance:.4f} | "
            f"{slip.params.ramp:.5f} | {slip.params.scale:.4f} | "
            f"{len(raw)} | "
            f"{100 * statistics.fmean(raw):.1f} % / {100 * max(raw):.1f} % | "
            f"{100 * statistics.fmean(fixed):.1f} % / {100 * max(fixed):.1f} % |"
        )
    return lines


def slip_summary(slip: SlipCalibration) -> str:
    """One line: the coefficients and the runs' odometry error before and after taking them out."""
    raw, fixed = slip.errors(corrected=False), slip.errors(corrected=True)
    return (
        f"roll {slip.params.roll:.4f} m/s, combined {slip.params.combined:.4f}, "
        f"compliance {slip.params.compliance:.4f} s, ramp {slip.params.ramp:.5f} s^3/m, "
        f"scale {slip.params.scale:.4f}; {len(raw)} runs, "
        f"encoder error {100 * statistics.fmean(raw):.1f} % -> {100 * statistics.fmean(fixed):.1f} % (mean)"
    )


def accuracy_json(result: CalibrationResult) -> dict[str, Any]:
    """Each accuracy check's summary and rows as plain data, by label."""
    return {
        label: {"summary": summarize(rows).as_dict(), "rows": [r.as_dict() for r in rows]}
        for label, rows in accuracy_entries(result)
    }


def runs_json(result: CalibrationResult) -> dict[str, Any]:
    """Every surface session's runs, fits and calibration as plain data (the JSON run log)."""

    def session(s: SurfaceSession) -> dict[str, Any]:
        return {
            "truth": s.truth,
            "calibration": describe_spec(s.spec),
            "deadband": s.fit.deadbands,
            "balance": None if s.fit.balance is None else s.fit.balance.as_dict(),
            "rollers": None if s.fit.rollers is None else s.fit.rollers.as_dict(),
            "roller_coast": None if s.fit.coast is None else s.fit.coast.as_dict(),
            "anchors": {f"course:{c:g}": asdict(a) for c, a in s.fit.anchors.items()},
            "reach": s.reach,
            "reach_moves": None
            if s.reach_moves is None
            else {
                "computed": {f"course:{c:g}": v for c, v in s.reach_moves.computed.items()},
                "measured": {f"course:{c:g}": v for c, v in s.reach_moves.measured.items()},
                "rows": [r.as_dict() for r in s.reach_moves.rows],
            },
            "k": s.fit.k,
            "rate_points": {g: [p.__dict__ for p in pts] for g, pts in s.fit.points.items()},
            "gyro": None if s.gyro is None else s.gyro.as_dict(),
            "odometry": None if s.odometry is None else s.odometry.as_dict(),
            "notes": s.notes,
            "runs": [r.as_dict() for r in s.runs],
        }

    out: dict[str, Any] = {
        "robot": result.robot.name,
        "surfaces": {s.surface: session(s) for s in result.sessions},
    }
    if result.average is not None:
        out["average"] = describe_spec(result.average)
    return out


# --------------------------------------------------------------------------- figures


def _factor_lines(ax: Any, table: PiecewiseLinear | None, label: str, style: str, color: str) -> None:
    if table is None:
        return
    ax.plot(table.x, table.y, style, color=color, marker=".", label=label)


def plot_rates(result: CalibrationResult, path: Path) -> None:
    """Seed 000's Fig. 5: rate against power for the straight courses and rotation."""
    from omnibot.plots import new_figure, save

    fig, axes = new_figure(1, 1, size=(7.5, 5.0))
    ax = axes[0][0]
    for k, s in enumerate(result.sessions):
        style = STYLES[k % len(STYLES)]
        for j, (group, pts) in enumerate(sorted(s.fit.points.items())):
            if not pts:
                continue
            curve = (
                s.fit.rotation if group == "rotation" else s.fit.translation.get(float(group.split(":")[1]))
            )
            color = f"C{j}"
            ax.plot([p.power for p in pts], [100 * p.rim for p in pts], "o", color=color, ms=4)
            if curve is not None:
                top = max(p.power for p in pts)
                xs = [curve.powers[0] + (top - curve.powers[0]) * i / 60 for i in range(61)]
                name = "rotation" if group == "rotation" else f"course {group.split(':')[1]} deg"
                ax.plot(
                    xs, [100 * curve.rim_at(x) for x in xs], style, color=color, label=f"{name}, {s.surface}"
                )
    ax.set_xlabel("power of the busiest motor [PWM counts]")
    ax.set_ylabel("rate [cm/s of rim speed, effective]")
    ax.set_title(f"{result.robot.name}: rate against power (seed 000 Fig. 5)", fontsize=10)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7, ncol=2)
    save(fig, str(path))


def _specs(result: CalibrationResult) -> list[tuple[str, CalibrationSpec, str]]:
    out = [(s.surface, s.spec, STYLES[(k + 1) % len(STYLES)]) for k, s in enumerate(result.sessions)]
    if result.average is not None:
        out.append(("average", result.average, STYLES[0]))
    return out


def plot_kt_kr(result: CalibrationResult, path: Path) -> None:
    """Seed 000's Fig. 6: K_t and K_r against power."""
    from omnibot.plots import new_figure, save

    fig, axes = new_figure(1, 1, size=(7.0, 4.6))
    ax = axes[0][0]
    for label, spec, style in _specs(result):
        _factor_lines(ax, spec.k_t, f"K_t, {label}", style, "C0")
        _factor_lines(ax, spec.k_r, f"K_r, {label}", style, "C3")
        if spec.motors is not None and spec.k_t is not None and spec.k_r is not None:
            # seed 000's K_r carries the motors' start, which the motor map's offsets hold here
            xs = list(spec.k_r.x)
            seed = PiecewiseLinear(x=tuple(xs), y=tuple(seed_kr(spec, xs)))
            _factor_lines(ax, seed, f"K_r with the offsets (seed 000's), {label}", style, "C1")
    ax.set_xlabel("uncalibrated power p = K |rim speed| [PWM counts]")
    ax.set_ylabel("factor")
    ax.set_ylim(0, 4)
    ax.set_title(f"{result.robot.name}: K_t and K_r (seed 000 Fig. 6)", fontsize=10)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7)
    save(fig, str(path))


def plot_kl(result: CalibrationResult, path: Path) -> None:
    """Seed 000's Fig. 7: K_l against power for each course."""
    from omnibot.plots import new_figure, save

    fig, axes = new_figure(1, 1, size=(7.0, 4.6))
    ax = axes[0][0]
    for label, spec, style in _specs(result):
        if spec.k_l is None:
            continue
        for j, (course, curve) in enumerate(zip(spec.k_l.courses_deg, spec.k_l.curves, strict=True)):
            _factor_lines(ax, curve, f"{course:g} deg, {label}", style, f"C{j}")
    ax.set_xlabel("uncalibrated power p = K |rim speed| [PWM counts]")
    ax.set_ylabel("K_l")
    ax.set_ylim(0, 4)
    ax.set_title(f"{result.robot.name}: K_l for each course (seed 000 Fig. 7)", fontsize=10)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7, ncol=2)
    save(fig, str(path))


def plot_accuracy(entries: Sequence[tuple[str, Sequence[AccuracyRow]]], path: Path) -> None:
    """MOVE distance error against course for every check (speeds as markers)."""
    from omnibot.plots import new_figure, save

    fig, axes = new_figure(1, 1, size=(7.5, 4.8))
    ax = axes[0][0]
    for k, (label, rows) in enumerate(entries):
        moves = [r for r in rows if r.kind == "move" and r.error is not None]
        if not moves:
            continue
        xs = [r.course_deg % 180.0 for r in moves]
        ax.plot(
            xs, [100 * (r.error or 0.0) for r in moves], "o", ms=3.5, color=f"C{k}", label=label, alpha=0.75
        )
    ax.axhspan(-3, 3, color="0.85", zorder=0, label="+-3 %")
    ax.set_xlabel("course [deg] (return runs folded onto their outbound course)")
    ax.set_ylabel("distance error [%]")
    ax.set_title("open-loop MOVE distance error, before and after calibration", fontsize=10)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7)
    save(fig, str(path))


def write_report(result: CalibrationResult, out: str | Path) -> list[Path]:
    """Write the report files (see the module docstring); returns their paths. The tables and raw
    data first; the figures only where matplotlib is installed (:func:`omnibot.plots.unavailable`
    says why not), so a calibration's report is never lost to a missing extra."""
    from omnibot.plots import unavailable

    out = Path(out)
    try:
        out.mkdir(parents=True, exist_ok=True)
        (out / "accuracy.md").write_text(accuracy_markdown(result), encoding="utf-8")
        (out / "accuracy.json").write_text(
            json.dumps(accuracy_json(result), indent=1, default=_json), encoding="utf-8"
        )
        (out / "runs.json").write_text(
            json.dumps(runs_json(result), indent=1, default=_json), encoding="utf-8"
        )
        tables = [out / "accuracy.md", out / "accuracy.json", out / "runs.json"]
        figures = _write_figures(result, out) if unavailable() is None else []
    except OSError as exc:
        raise ConfigError(f"cannot write the report to {out}: {exc.strerror}", key="--report") from None
    return figures + tables


def _write_figures(result: CalibrationResult, out: Path) -> list[Path]:
    """Seed 000's figures 5-7 and, with accuracy checks, the before/after chart; their paths."""
    written = []
    for name, fn in (
        ("fig5_rates.png", plot_rates),
        ("fig6_kt_kr.png", plot_kt_kr),
        ("fig7_kl.png", plot_kl),
    ):
        fn(result, out / name)
        written.append(out / name)
    entries = accuracy_entries(result)
    if entries:
        plot_accuracy(entries, out / "accuracy.png")
        written.append(out / "accuracy.png")
    return written


def _json(value: Any) -> Any:
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, tuple):
        return list(value)
    raise TypeError(f"not JSON: {type(value).__name__}")


def reach_lines(result: CalibrationResult) -> list[str]:
    """The report's reach section: each calibration's reach per folded course (driven), else the one
    computed from the tables."""
    rows = [(f"{s.surface} calibration", s.spec, s.reach) for s in result.sessions]
    if result.average is not None and result.sessions:
        length = result.sessions[0].fit.move_length
        rows.append(
            ("average calibration", result.average, reach_speed(result.robot, result.average, length))
        )
    out = [
        "## Reach",
        "",
        "The fastest MOVE of the reference length that lands within the calibration's goal on each folded",
        "course, driven and slowed until it did (the controller runs a MOVE asked faster at it, warning 18);",
        "where it was not driven, the fastest the tables power on every course without a motor saturating.",
        "",
        "| calibration | m/s |",
        "|---|---|",
    ]
    for label, spec, computed in rows:
        if spec.reach is not None:
            cells = describe_reach(spec.reach)
        else:
            cells = "-" if computed is None else f"{computed:g} (computed, every course)"
        out.append(f"| {label} | {cells} |")
    return out
