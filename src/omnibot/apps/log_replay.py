"""``omnibot log replay``: an estimator, and a follower, re-run on a run's recorded telemetry and cycles,
compared with what the run estimated and commanded (:mod:`omnibot.logs.replay`,
:mod:`omnibot.logs.follower_replay`).
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any

from omnibot.apps.log_views import EXIT_FAILED, EXIT_OK, load, write_csv
from omnibot.errors import ConfigError
from omnibot.logs import Run
from omnibot.motion import Twist

if TYPE_CHECKING:
    from omnibot.logs import RecordedFollower


def _replay(args: argparse.Namespace, run: Run | None = None) -> int:
    from omnibot.logs import replay_log, truth_in_frame

    run = load(args) if run is None else run
    result = replay_log(run, args.estimator)
    if not result.estimates:
        print(f"omnibot: error: {args.file} has no telemetry with encoders to replay", file=sys.stderr)
        return EXIT_FAILED
    if args.csv:
        from omnibot.outputs import check_writable

        check_writable(args.csv, "--csv")
        rows = [[t, e.t, e.x, e.y, e.theta, e.vx, e.vy, e.w] for t, e in result.estimates]
        write_csv(Path(args.csv), ["t", "controller_time", "x", "y", "theta", "vx", "vy", "w"], rows)
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


def replay_all(args: argparse.Namespace) -> int:
    """``omnibot log replay``: the estimator, then each follower run asked for."""
    """``omnibot log replay``: the estimator, then the follower (when the log has a follower run or
    one is asked for); the worse of the two statuses."""
    from omnibot.logs import make_replayed, parse_options, recorded_followers

    run = load(args)
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
        write_csv(Path(args.commands_csv), header, rows)
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
