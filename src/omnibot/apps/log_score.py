"""``omnibot log score``: a SLAM run (omnibot's or slam_toolbox's...) scored from its logs: APE/RPE
against the truth, the map against the world (:mod:`omnibot.logs.slamscore`).
"""

from __future__ import annotations

import argparse
import math

EXIT_OK = 0


def score(args: argparse.Namespace) -> int:
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
