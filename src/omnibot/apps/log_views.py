"""``omnibot log info``, ``protocol``, ``export``, ``plot`` and ``recover``: one recorded run looked at
(its figures, its byte trace, its records as CSV, its plot) or rewritten whole; :func:`load` reads
it for every subcommand.

Each subcommand reads the whole log once (:func:`omnibot.logs.run.load_run`); a file cut short by a
crash is read up to its last chunk, and every subcommand says so on stderr.
"""

from __future__ import annotations

import argparse
import csv
import math
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from omnibot.errors import ConfigError
from omnibot.logs import Run, keyword_counts, load_run, rate_and_gap
from omnibot.transport import SpyEvent, format_event

EXIT_OK, EXIT_FAILED = 0, 1


def load(args: argparse.Namespace) -> Run:
    """The run in ``args.file``, with a warning on stderr when it was cut short."""
    run = load_run(args.file)
    if run.cut_short:
        print(
            f"omnibot: warning: {args.file} was cut short ({run.cut_short}); read up to its last chunk",
            file=sys.stderr,
        )
    return run


# --------------------------------------------------------------------------- info


def info_lines(run: Run) -> list[str]:
    """The report of ``omnibot log info``."""
    meta = run.omnibot_metadata()
    lines = [
        f"file      {run.path}" + ("  (cut short: read up to its last chunk)" if run.cut_short else ""),
        f"robot     {meta.get('robot', '?')} on {meta.get('url', '?')} (omnibot {meta.get('version', '?')})",
        f"duration  {run.duration:.3f} s, {sum(len(v) for v in run.times.values())} messages",
        "",
        f"{'topic':24s} {'type':34s} {'count':>7s} {'rate Hz':>8s} {'max gap s':>9s}",
    ]
    for topic in sorted(run.topics):
        times = run.times[topic]
        rate, gap = rate_and_gap(times)
        lines.append(f"{topic:24s} {run.topics[topic]:34s} {len(times):7d} {rate:8.1f} {gap:9.3f}")
    commands, events = keyword_counts(run, "command"), keyword_counts(run, "event")
    replies = keyword_counts(run, "reply")
    lines += [
        "",
        "protocol  commands " + _counts(commands),
        "          replies  " + _counts(replies),
        "          events   " + _counts(events),
    ]
    tx = sum(len(d) for _, k, d, _ in run.link if k == "TX")
    rx = sum(len(d) for _, k, d, _ in run.link if k == "RX")
    link_errors = [note for _, k, _, note in run.link if k == "ERR"]
    tel = [t for t, d, kw, _ in run.protocol if d == "event" and kw == "TEL"]
    rate, gap = rate_and_gap(tel)
    unanswered = sum(commands.values()) - sum(replies.values())
    lines += [
        f"link      {tx} bytes sent, {rx} received ({(tx + rx) / run.duration if run.duration else 0:.0f} B/s); "
        f"{len(link_errors)} link errors; {events.get('MALFORMED', 0)} malformed; "
        f"{max(0, unanswered)} commands without a reply",
        f"          telemetry {len(tel)} samples at {rate:.1f} Hz, longest gap {gap:.3f} s"
        if tel
        else "          telemetry: no data (no TEL samples: no estimate, wheels or sonar in this log)",
    ]
    if run.control:
        lines.append(f"control   {len(run.control)} changes of the source in control")
        lines += [
            f"  {t:10.3f} {source or '(nobody)':10s} {reason}" for t, source, reason, _ in run.control[:20]
        ]
    problems = run.problems()
    lines.append(f"problems  {len(problems)} (warnings, errors, malformed, link errors)")
    lines += [f"  {t:10.3f} {kind:10s} {text}" for t, kind, text in problems[:20]]
    if len(problems) > 20:
        lines.append(f"  ... {len(problems) - 20} more")
    return lines


def _counts(counts: dict[str, int]) -> str:
    return ", ".join(f"{k} {v}" for k, v in sorted(counts.items())) or "none"


def info(args: argparse.Namespace) -> int:
    """``omnibot log info``."""
    run = load(args)
    if not run.topics:
        print(f"omnibot: error: {args.file}: no data (no messages)", file=sys.stderr)
        return EXIT_FAILED
    print("\n".join(info_lines(run)))
    return EXIT_OK


# --------------------------------------------------------------------------- protocol


def protocol(args: argparse.Namespace) -> int:
    """``omnibot log protocol``."""
    run = load(args)
    if not run.link:
        raise ConfigError(f"{args.file} has no link bytes (/omnibot/link)", key="FILE")
    t0 = run.link[0][0]
    for t, kind, data, note in run.link:
        event = SpyEvent(t - t0, kind if kind in ("TX", "RX", "ERR", "CLOSE") else "ERR", data, note)  # type: ignore[arg-type]
        for line in format_event(event):
            print(line)
    return EXIT_OK


# --------------------------------------------------------------------------- export


def write_csv(path: Path, header: list[str], rows: Sequence[Sequence[object]]) -> None:
    """``rows`` under ``header`` into the CSV file ``path``."""
    with path.open("w", newline="", encoding="utf-8") as f:
        w = csv.writer(f)
        w.writerow(header)
        w.writerows(rows)


def export_csv(run: Run, out: Path) -> list[Path]:
    """One CSV per kind of record (and the URDF and calibration as files); the paths written."""
    written: list[Path] = []

    def put(name: str, header: list[str], rows: list[list[object]]) -> None:
        if rows:
            write_csv(out / name, header, rows)
            written.append(out / name)

    pose = ["t", "x", "y", "theta", "vx", "vy", "w"]
    put("odom.csv", pose, [list(r) for r in run.estimate])
    put("truth.csv", pose, [list(r) for r in run.truth])
    if run.joints:
        names = run.joints[0][1]
        header = ["t"] + [f"{n}_{q}" for q in ("position", "velocity", "effort") for n in names]
        put("joint_states.csv", header, [[t, *p, *v, *e] for t, _, p, v, e in run.joints])
    put("imu.csv", ["t", "yaw_rate", "yaw"], [list(r) for r in run.imu])
    put("cmd_vel.csv", ["t", "vx", "vy", "w"], [list(r) for r in run.cmd_vel])
    for sonar, rows in sorted(run.ranges.items()):
        put(f"range_{sonar}.csv", ["t", "range"], [list(r) for r in rows])
    put("protocol.csv", ["t", "direction", "keyword", "text"], [list(r) for r in run.protocol])
    put("control.csv", ["t", "source", "reason", "lock"], [list(r) for r in run.control])
    put("link.csv", ["t", "kind", "hex", "note"], [[t, k, d.hex(" "), n] for t, k, d, n in run.link])
    for name, text in (("robot.urdf", run.robot_description), ("calibration.yaml", run.calibration)):
        if text:
            (out / name).write_text(text, encoding="utf-8")
            written.append(out / name)
    return written


def export(args: argparse.Namespace) -> int:
    """``omnibot log export``."""
    from omnibot.cliargs import output_dir
    from omnibot.outputs import made_directory

    run = load(args)
    out = output_dir(args.csv, "--csv")
    try:
        written = export_csv(run, made_directory(out, "--csv"))
    except OSError as exc:
        raise ConfigError(f"cannot write in {out}: {exc.strerror or exc}", key="--csv") from None
    for path in written:
        print(path)
    return EXIT_OK


# --------------------------------------------------------------------------- plot


def plot_run(run: Run, path: str) -> None:
    """Estimate against truth, wheel speeds, powers, problems over time: one PNG."""
    from omnibot.plots import new_figure, save

    fig, ax = new_figure(2, 2, size=(12.0, 8.0))
    xy = ax[0][0]
    if run.truth:
        xy.plot([r[1] for r in run.truth], [r[2] for r in run.truth], "k-", label="truth (simulator)")
    if run.estimate:
        xy.plot([r[1] for r in run.estimate], [r[2] for r in run.estimate], "C0--", label="estimate (odom)")
    xy.set(xlabel="x (m)", ylabel="y (m)", title="estimate against truth", aspect="equal")
    _legend(xy)
    wheels, powers, problems = ax[0][1], ax[1][0], ax[1][1]
    if run.joints:
        t = [j[0] for j in run.joints]
        for i, name in enumerate(run.joints[0][1]):
            wheels.plot(t, [j[3][i] for j in run.joints], label=name)
            if run.joints[0][4]:
                powers.plot(t, [j[4][i] if i < len(j[4]) else math.nan for j in run.joints], label=name)
        _legend(wheels)
        _legend(powers)
    wheels.set(xlabel="t (s)", ylabel="rad/s", title="wheel speeds")
    powers.set(xlabel="t (s)", ylabel="PWM counts", title="motor powers")
    kinds = sorted({k for _, k, _ in run.problems()})
    for i, kind in enumerate(kinds):
        times = [t for t, k, _ in run.problems() if k == kind]
        problems.plot(times, [i] * len(times), "|", markersize=12, label=kind)
    problems.set(
        xlabel="t (s)",
        title=f"link errors, warnings ({len(run.problems())})",
        xlim=(0, max(run.duration, 1e-3)),
    )
    problems.set_yticks(range(len(kinds)), kinds)
    save(fig, path)


def _legend(ax: Any) -> None:
    """A legend where something was drawn (matplotlib warns on stderr about an empty one: a log
    without powers, VEL on the wheel loop, or a log cut before its first sample)."""
    if ax.get_legend_handles_labels()[0]:
        ax.legend(loc="best", fontsize=8)


def plot(args: argparse.Namespace) -> int:
    """``omnibot log plot``."""
    from omnibot.cliargs import check_distinct, check_plot

    check_plot(args.plot, "-o")
    check_distinct([("-o", args.plot)], [("FILE.mcap", args.file)])
    run = load(args)
    if not (run.estimate or run.truth or run.joints):
        print(
            f"omnibot: error: {args.file}: no data to plot (no estimate, truth or wheel telemetry: "
            "the log holds only " + (", ".join(sorted(run.topics)) or "no messages") + ")",
            file=sys.stderr,
        )
        return EXIT_FAILED
    try:
        plot_run(run, args.plot)
    except OSError as exc:
        raise ConfigError(f"cannot write {args.plot}: {exc.strerror or exc}", key="-o") from None
    print(f"wrote {args.plot}", file=sys.stderr)
    return EXIT_OK


# --------------------------------------------------------------------------- recover


def recover(args: argparse.Namespace) -> int:
    """``omnibot log recover``."""
    from omnibot.logs.recover import recover
    from omnibot.outputs import check_writable

    check_writable(args.out, "-o")
    result = recover(args.file, args.out, force=args.force)
    if result.cut_short is None and not args.force:
        print(f"{result.source} is whole (it has its summary): nothing to recover")
        return EXIT_OK
    if result.cut_short is not None and result.messages == 0:
        result.target.unlink()  # made by recover() alone ('xb'): a file of no message is no recovery
        print(
            f"omnibot: error: {result.source}: no message before the cut (the log was cut short: "
            f"{result.cut_short}): nothing to recover, nothing written",
            file=sys.stderr,
        )
        return EXIT_FAILED
    print(
        f"wrote {result.target}: {result.messages} messages, {result.duration:.3f} s"
        + (f" (the log was cut short: {result.cut_short})" if result.cut_short else "")
    )
    return EXIT_OK
