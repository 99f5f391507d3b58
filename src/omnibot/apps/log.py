"""``omnibot log``: inspect, plot, export, print and replay a recorded run (``--log FILE.mcap``).

The options of every subcommand are declared here; the subcommands are :mod:`omnibot.apps.log_views`
(``info``, ``protocol``, ``export``, ``plot``, ``recover``), :mod:`omnibot.apps.log_replay` and
:mod:`omnibot.apps.log_score`.
"""

from __future__ import annotations

import argparse

from omnibot.apps import log_views
from omnibot.apps.log_replay import replay_all
from omnibot.apps.log_score import score as score_logs


def add_log_command(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Add ``omnibot log`` and its subcommands (info, plot, export, protocol, replay, recover, score) to
    ``sub``."""
    p = sub.add_parser("log", help="inspect, plot, export and replay a run recorded with --log FILE.mcap")
    lsub = p.add_subparsers(
        dest="log_command", required=True, metavar="{info,plot,export,protocol,replay,recover,score}"
    )
    info = lsub.add_parser("info", help="duration, channels, rates, gaps, errors and warnings, link health")
    info.set_defaults(handler=log_views.info)
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
    plot.set_defaults(handler=log_views.plot)
    export = lsub.add_parser("export", help="write the records as CSV files")
    export.add_argument("--csv", required=True, metavar="DIR", help="directory for the CSV files")
    export.set_defaults(handler=log_views.export)
    proto = lsub.add_parser("protocol", help="the byte trace both ways, as spy+ prints it")
    proto.set_defaults(handler=log_views.protocol)
    replay = _add_replay_command(lsub)
    rec = lsub.add_parser("recover", help="rewrite a log cut short (SIGKILL) whole, for rosbags and ros2 bag")
    rec.add_argument(
        "-o", "--out", metavar="OUT.mcap", help="the file to write (default FILE-recovered.mcap beside it)"
    )
    rec.add_argument("--force", action="store_true", help="rewrite a whole log too")
    rec.set_defaults(handler=log_views.recover)
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
    replay.set_defaults(handler=replay_all)
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
    score.set_defaults(handler=score_logs)
