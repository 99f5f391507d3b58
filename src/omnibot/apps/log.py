"""``omnibot log``: inspect, plot, export, print and replay a recorded run (``--log FILE.mcap``).

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
from typing import TYPE_CHECKING, Any

from omnibot.errors import ConfigError
from omnibot.logs import Run, keyword_counts, load_run, rate_and_gap
from omnibot.motion import Twist
from omnibot.transport import SpyEvent, format_event

if TYPE_CHECKING:
    from omnibot.logs import RecordedFollower

EXIT_OK, EXIT_FAILED = 0, 1


def _load(args: argparse.Namespace) -> Run:
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


def _info(args: argparse.Namespace) -> int:
    run = _load(args)
    if not run.topics:
        print(f"omnibot: error: {args.file}: no data (no messages)", file=sys.stderr)
        return EXIT_FAILED
    print("\n".join(info_lines(run)))
    return EXIT_OK


# --------------------------------------------------------------------------- protocol


def _protocol(args: argparse.Namespace) -> int:
    run = _load(args)
    if not run.link:
        raise ConfigError(f"{args.file} has no link bytes (/omnibot/link)", key="FILE")
    t0 = run.link[0][0]
    for t, kind, data, note in run.link:
        event = SpyEvent(t - t0, kind if kind in ("TX", "RX", "ERR", "CLOSE") else "ERR", data, note)  # type: ignore[arg-type]
        for line in format_event(event):
            print(line)
    return EXIT_OK


# --------------------------------------------------------------------------- export


def _write_csv(path: Path, header: list[str], rows: Sequence[Sequence[object]]) -> None:
    with path.open("w", newline="", encoding="utf-8") as f:
        w = csv.writer(f)
        w.writerow(header)
        w.writerows(rows)


def export_csv(run: Run, out: Path) -> list[Path]:
    """One CSV per kind of record (and the URDF and calibration as files); the paths written."""
    written: list[Path] = []

    def put(name: str, header: list[str], rows: list[list[object]]) -> None:
        if rows:
            _write_csv(out / name, header, rows)
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


def _export(args: argparse.Namespace) -> int:
    from omnibot.cliargs import output_dir

    run = _load(args)
    out = output_dir(args.csv, "--csv")
    try:
        written = export_csv(run, out)
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


def _plot(args: argparse.Namespace) -> int:
    from omnibot.cliargs import check_distinct, check_plot

    check_plot(args.plot, "-o")
    check_distinct([("-o", args.plot)], [("FILE.mcap", args.file)])
    run = _load(args)
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


# --------------------------------------------------------------------------- replay


def _replay(args: argparse.Namespace, run: Run | None = None) -> int:
    from omnibot.logs import replay_log, truth_in_frame

    run = _load(args) if run is None else run
    result = replay_log(run, args.estimator)
    if not result.estimates:
        print(f"omnibot: error: {args.file} has no telemetry with encoders to replay", file=sys.stderr)
        return EXIT_FAILED
    if args.csv:
        from omnibot.outputs import check_writable

        check_writable(args.csv, "--csv")
        rows = [[t, e.t, e.x, e.y, e.theta, e.vx, e.vy, e.w] for t, e in result.estimates]
        _write_csv(Path(args.csv), ["t", "controller_time", "x", "y", "theta", "vx", "vy", "w"], rows)
    last = result.estimates[-1][1]
    print(
        f"replayed {len(result.estimates)} telemetry samples with {result.estimator}: "
        f"final pose x={last.x:.4f} m y={last.y:.4f} m theta={math.degrees(last.theta):.2f} deg"
    )
    truth = truth_in_frame(run, result)
    if truth:  # the simulator's, moved into the estimate's frame (it started where the estimate did)
        _, x, y, theta = truth[-1]
        print(
            f"truth at the end (in the estimate's frame): x={x:.4f} m y={y:.4f} m "
            f"theta={math.degrees(theta):.2f} deg; error {math.hypot(x - last.x, y - last.y):.4f} m"
        )
    if result.note:
        print(result.note)
    if result.max_difference is None:
        return EXIT_OK
    if result.max_difference == 0.0:
        print("the live estimate is reproduced exactly")
        return EXIT_OK
    print(
        f"omnibot: error: the replay differs from the live estimate by up to {result.max_difference:g}",
        file=sys.stderr,
    )
    return EXIT_FAILED


def _replay_all(args: argparse.Namespace) -> int:
    """``omnibot log replay``: the estimator, then the follower (when the log has a follower run or
    one is asked for); the worse of the two statuses."""
    from omnibot.logs import make_replayed, parse_options, recorded_followers

    run = _load(args)
    runs = recorded_followers(run)
    asked = args.follower is not None or args.follower_option or args.commands_csv or args.run
    chosen: RecordedFollower | None = None
    if runs:
        number = args.run or runs[0].run
        found = [r for r in runs if r.run == number]
        if not found:
            numbers = ", ".join(str(r.run) for r in runs)
            raise ConfigError(f"{args.file} has follower runs {numbers}, not {number}", key="--run")
        chosen = found[0]
    elif asked:
        raise ConfigError(
            f"{args.file} has no follower run (record `omnibot follow` or `run --follow` with --log)",
            key="--follower",
        )
    options = parse_options(args.follower_option)
    if chosen is not None:
        make_replayed(chosen, args.follower, options)  # a bad follower or option: said before anything runs
    from omnibot.cliargs import check_distinct

    check_distinct([("--csv", args.csv), ("--commands-csv", args.commands_csv)], [("FILE.mcap", args.file)])
    if args.commands_csv:
        from omnibot.outputs import check_writable

        check_writable(args.commands_csv, "--commands-csv")
    status = _replay(args, run)
    if chosen is not None:
        status = max(status, _replay_follower(args, chosen, options, len(runs)))
    return status


def _replay_follower(
    args: argparse.Namespace, chosen: RecordedFollower, options: dict[str, Any], runs: int
) -> int:
    """Re-run the recorded follower (or ``--follower`` with ``--follower-option``s) on the recorded
    cycles; 1 when the live follower's own commands are not reproduced exactly."""
    from omnibot.logs import replay_follower

    result = replay_follower(chosen, args.follower, options)
    rec = result.recorded
    if runs > 1:
        print(f"follower run {rec.run} of {runs} (--run N for another)")
    if args.commands_csv:
        rows = [[r.t, r.source, *(_xyw(r.live)), *(_xyw(r.replayed))] for r in result.rows]
        header = ["t", "in_control", "live_vx", "live_vy", "live_w", "replay_vx", "replay_vy", "replay_w"]
        _write_csv(Path(args.commands_csv), header, rows)
    options_text = ", ".join(f"{k}={v}" for k, v in sorted(result.options.items()))
    print(
        f"replayed follower {result.follower} ({options_text}) on {len(result.rows)} cycles "
        f"of {rec.follower} following a {rec.path.length:.2f} m path"
    )
    if result.is_live:
        if result.reproduced:
            print(f"the live follower's commands are reproduced exactly ({result.compared} cycles)")
            return EXIT_OK
        print(
            f"omnibot: error: the replay differs from the live follower's commands by up to "
            f"{result.max_difference:g} over {result.compared} cycles",
            file=sys.stderr,
        )
        return EXIT_FAILED
    rx, ry, rw = result.rms
    silent = sum(1 for r in result.rows if r.live is not None and r.replayed is None)
    print(
        f"against the live commands over the {result.compared} cycles the live follower drove"
        + (f" ({silent} where the replayed one had fallen silent)" if silent else "")
        + f": RMS difference vx {rx:.4f} m/s, vy {ry:.4f} m/s, w {rw:.4f} rad/s"
    )
    ended = (
        "never fell silent" if result.finished_at is None else f"fell silent at t={result.finished_at:.3f} s"
    )
    print(f"  it {ended}; open loop: the robot moved as the live commands drove it, not as these would have")
    return EXIT_OK


def _xyw(twist: Twist | None) -> list[object]:
    if twist is None:
        return ["", "", ""]
    return [twist.vx, twist.vy, twist.w]


# --------------------------------------------------------------------------- recover


def _recover(args: argparse.Namespace) -> int:
    from omnibot.logs.recover import recover
    from omnibot.outputs import check_writable

    check_writable(args.out, "-o")
    result = recover(args.file, args.out, force=args.force)
    if result.cut_short is None and not args.force:
        print(f"{result.source} is whole (it has its summary): nothing to recover")
        return EXIT_OK
    print(
        f"wrote {result.target}: {result.messages} messages, {result.duration:.3f} s"
        + (f" (the log was cut short: {result.cut_short})" if result.cut_short else "")
    )
    return EXIT_OK


# --------------------------------------------------------------------------- score


def _score(args: argparse.Namespace) -> int:
    """``omnibot log score``: a SLAM run scored from its logs (see :mod:`omnibot.logs.slamscore`)."""
    from omnibot.cliargs import output_dir
    from omnibot.logs import Frames, score_slam_logs
    from omnibot.mapping import score_lines
    from omnibot.motion import Pose2D, parse_pose

    world = None
    if args.world is not None:
        from omnibot.sim import load_world

        world = load_world(args.world)
    grid = None
    if args.map is not None:
        from omnibot.mapping import load_map

        grid = load_map(args.map)
    map_pose = None
    if args.map_pose is not None:
        x, y, theta = parse_pose(args.map_pose, "--map-pose")
        map_pose = Pose2D(x, y, theta or 0.0)
    out = output_dir(args.out)
    frames = Frames.prefixed(args.frame_prefix)
    result = score_slam_logs(args.file, out, world=world, grid=grid, map_pose=map_pose, frames=frames)
    report = result.report
    where = report["map_frame_in_world"]
    print(
        f"score: {report['corrections']} {frames.map} -> {frames.odom} corrections, {report['scans']} scans, "
        f"{report['distance_m']:.1f} m along the estimate"
        + (
            ""
            if where is None
            else f"; the map frame at ({where[0]:.3f}, {where[1]:.3f}, "
            f"{math.degrees(where[2]):.1f} deg) in the world"
        )
    )
    for line in score_lines(report):
        print(f"score: {line}")
    print(f"score: wrote {', '.join(str(f) for f in result.files)}")
    return EXIT_OK


# --------------------------------------------------------------------------- parser


def add_log_command(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Add ``omnibot log`` and its subcommands (info, plot, export, protocol, replay, recover, score) to
    ``sub``."""
    p = sub.add_parser("log", help="inspect, plot, export and replay a run recorded with --log FILE.mcap")
    lsub = p.add_subparsers(
        dest="log_command", required=True, metavar="{info,plot,export,protocol,replay,recover,score}"
    )
    info = lsub.add_parser("info", help="duration, channels, rates, gaps, errors and warnings, link health")
    info.set_defaults(handler=_info)
    plot = lsub.add_parser(
        "plot", help="estimate against truth, wheel speeds and powers, link errors over time"
    )
    plot.add_argument(
        "-o",
        "--out",
        dest="plot",
        default="log.png",
        metavar="FILE.png",
        help="the plot to write (default log.png)",
    )
    plot.set_defaults(handler=_plot)
    export = lsub.add_parser("export", help="write the records as CSV files")
    export.add_argument("--csv", required=True, metavar="DIR", help="directory for the CSV files")
    export.set_defaults(handler=_export)
    proto = lsub.add_parser("protocol", help="the byte trace both ways, as spy+ prints it")
    proto.set_defaults(handler=_protocol)
    replay = _add_replay_command(lsub)
    rec = lsub.add_parser("recover", help="rewrite a log cut short (SIGKILL) whole, for rosbags and ros2 bag")
    rec.add_argument(
        "-o", "--out", metavar="OUT.mcap", help="the file to write (default FILE-recovered.mcap beside it)"
    )
    rec.add_argument("--force", action="store_true", help="rewrite a whole log too")
    rec.set_defaults(handler=_recover)
    for q in (info, plot, export, proto, replay, rec):
        q.add_argument("file", metavar="FILE.mcap", help="a log written with --log")
    _add_score_command(lsub)


def _add_replay_command(lsub: argparse._SubParsersAction[argparse.ArgumentParser]) -> argparse.ArgumentParser:
    """``omnibot log replay``'s options (its log file aside)."""
    replay = lsub.add_parser(
        "replay", help="re-run an estimator, and a follower, on the recorded telemetry and cycles"
    )
    replay.add_argument("--estimator", help="the estimator to run (default: the one recorded)")
    replay.add_argument("--csv", metavar="FILE.csv", help="write the replayed estimate")
    replay.add_argument("--follower", help="the follower to run (default: the one recorded)")
    replay.add_argument(
        "--follower-option",
        action="append",
        metavar="KEY=VALUE",
        help="a follower option (repeatable), e.g. cross=30 or heading_gains=[4,0.5,0.1]",
    )
    replay.add_argument("--run", type=int, metavar="N", help="the follower run to replay (default the first)")
    replay.add_argument(
        "--commands-csv", metavar="FILE.csv", help="write the live and the replayed follower's commands"
    )
    replay.set_defaults(handler=_replay_all)
    return replay


def _add_score_command(lsub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """``omnibot log score``: a SLAM run's logs against the truth and the world."""
    score = lsub.add_parser(
        "score",
        help="score a SLAM run (slam_toolbox's...) from its logs: APE/RPE against the truth, the map "
        "against the world",
    )
    score.add_argument(
        "file",
        nargs="+",
        metavar="FILE.mcap",
        help="the logs (omnibot's --log with the truth, a ros2 bag of /tf and /map: MCAP files or rosbag2 "
        "directories), read together",
    )
    score.add_argument(
        "--out", required=True, metavar="DIR", help="where the map, trajectories and report go"
    )
    score.add_argument(
        "--world", metavar="NAME|FILE", help="the simulated world, for the map's precision and recall"
    )
    score.add_argument(
        "--map", metavar="MAP.yaml", help="the SLAM's saved map (default: the logs' last /map)"
    )
    score.add_argument(
        "--map-pose",
        metavar="X,Y,THETA",
        help="the map frame's pose in the world, m, m, degrees (default: where the truth puts the odometry "
        "frame at the start)",
    )
    score.add_argument(
        "--frame-prefix",
        default="",
        metavar="P",
        help="the frames' prefix on /tf (r1/: r1/map, r1/odom, r1/base_link)",
    )
    score.set_defaults(handler=_score)
