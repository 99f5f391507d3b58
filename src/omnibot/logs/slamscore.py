"""Scoring a SLAM that ran outside omnibot (slam_toolbox over ROS 2) from its logs, as ``omnibot map``
scores its own: ``omnibot log score``.

What is read, from one or more MCAP files (omnibot's ``--log``, ``ros2 bag record -s mcap``'s files, or
a rosbag2 directory of them), merged by stamp::

    /tf             map -> odom (the SLAM's correction) and odom -> base_link (the odometry it used)
    /odom           nav_msgs/Odometry: the odometry trajectory (odom -> base_link from /tf without it)
    /map            nav_msgs/OccupancyGrid: the SLAM's map (the last one; or ``map_file``)
    /omnibot/truth  nav_msgs/Odometry: the simulator's true pose (omnibot's logs on the simulator)

The estimate is ``map -> odom`` (interpolated between its stamps, the last one held after them)
composed with each ``odom -> base_link`` from the first ``map -> odom`` on. The map frame of a SLAM
node is its own (slam_toolbox's: the odometry frame where it started), the truth's is the world's: the
map frame is placed in the world at ``map_pose``, by default where the truth puts the odometry frame
at the first odometry sample (``truth o odometry^-1``: the odometry has not drifted yet). Then the
same report as ``omnibot map``'s (:func:`omnibot.mapping.report.write_report`): the trajectories in
TUM, APE/RPE of the estimate and of the odometry against the truth, the map's precision and recall
against the world's geometry.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from omnibot.errors import ConfigError
from omnibot.logs.reader import LogFile
from omnibot.logs.run import yaw_of
from omnibot.logs.topics import MAP, ODOM, SCAN, TF, TRUTH
from omnibot.mapping import (
    MappingResult,
    OccupancyGrid,
    Track,
    compose,
    interpolate,
    inverse,
    path_length,
    write_report,
)
from omnibot.motion import Pose2D

TF_TYPE = "tf2_msgs/msg/TFMessage"


@dataclass(frozen=True)
class Frames:
    """The frame names to look for on ``/tf`` (a frame prefix included: ``r1/map``)."""

    map: str = "map"
    odom: str = "odom"
    base: str = "base_link"

    @classmethod
    def prefixed(cls, prefix: str) -> Frames:
        """The default frames with ``prefix`` (``r1/``) before each."""
        return cls(prefix + "map", prefix + "odom", prefix + "base_link")


@dataclass
class SlamLog:
    """What the logs hold of a SLAM run (times in s on the logs' stamps)."""

    map_to_odom: Track
    odom_to_base: Track
    """odom -> base_link from /tf (the odometry the SLAM was given)."""
    odometry: Track
    """/odom's poses (odom_to_base when the logs have no /odom)."""
    truth: Track
    grid: OccupancyGrid | None
    scans: int

    def estimate(self) -> Track:
        """The SLAM's map-frame pose at every odom -> base_link sample from its first correction on."""
        out = Track()
        m2o = self.map_to_odom
        if not len(m2o):
            return out
        for t, odom in zip(self.odom_to_base.stamps, self.odom_to_base.poses, strict=True):
            if t < m2o.stamps[0]:
                continue
            correction = interpolate(m2o.stamps, m2o.poses, t) if t <= m2o.stamps[-1] else m2o.poses[-1]
            assert correction is not None
            out.add(t, compose(correction, odom))
        return out

    def start_pose(self) -> Pose2D:
        """The odometry frame's pose in the truth's frame at the first odometry sample (see the
        module docstring); ConfigError when the truth does not cover it."""
        track = self.odom_to_base if len(self.odom_to_base) else self.odometry
        for t, odom in zip(track.stamps, track.poses, strict=True):
            true = interpolate(self.truth.stamps, self.truth.poses, t)
            if true is not None:
                return compose(true, inverse(odom))
        raise ConfigError("the truth and the odometry do not overlap in time: give --map-pose X,Y,THETA")


def _stamp(header: Any) -> float:
    return float(header.stamp.sec) + 1e-9 * float(header.stamp.nanosec)


def _pose(position: Any, orientation: Any) -> Pose2D:
    return Pose2D(float(position.x), float(position.y), yaw_of(orientation))


def grid_of(msg: Any) -> OccupancyGrid:
    """An :class:`OccupancyGrid` of a nav_msgs/OccupancyGrid (row 0 at the bottom, as both have it)."""
    info = msg.info
    data = np.asarray(msg.data, dtype=np.int16).reshape(int(info.height), int(info.width))
    data = np.where((data < -1) | (data > 100), -1, data)  # out-of-range values are unknown
    origin = _pose(info.origin.position, info.origin.orientation)
    # the message's resolution is a float32 (0.05 arrives as 0.0500000007): taken as the decimal it
    # stands for, or a 5 cm tolerance would no longer reach the next 5 cm cell
    resolution = float(str(np.float32(info.resolution)))
    return OccupancyGrid(data.astype(np.int8), resolution, origin, msg.header.frame_id.lstrip("/"))


def log_files(paths: Iterable[str | Path]) -> list[Path]:
    """The MCAP files of ``paths`` (a rosbag2 directory: its ``*.mcap``); ConfigError for none."""
    files: list[Path] = []
    for path in map(Path, paths):
        found = sorted(path.glob("*.mcap")) if path.is_dir() else [path]
        if path.is_dir() and not found:
            raise ConfigError(f"no MCAP file in {path}", key="FILE")
        files += found
    return files


def _sorted(samples: list[tuple[float, Pose2D]]) -> Track:
    track = Track()
    for t, pose in sorted(samples, key=lambda s: s[0]):
        if not track.stamps or t > track.stamps[-1]:
            track.add(t, pose)
    return track


def read_slam_logs(
    paths: Sequence[str | Path],
    *,
    frames: Frames | None = None,
    odom_topic: str = ODOM,
    map_topic: str = MAP,
    truth_topic: str = TRUTH,
) -> SlamLog:
    """Read what :class:`SlamLog` holds from the logs at ``paths`` (see the module docstring)."""
    frames = frames or Frames()
    topics = {TF, odom_topic, map_topic, truth_topic, SCAN}
    m2o: list[tuple[float, Pose2D]] = []
    o2b: list[tuple[float, Pose2D]] = []
    odom: list[tuple[float, Pose2D]] = []
    truth: list[tuple[float, Pose2D]] = []
    grid: tuple[float, Any] | None = None
    scans = 0
    for path in log_files(paths):
        for message in LogFile.open(path).messages(topics):
            if message.topic == SCAN:
                scans += 1
                continue
            msg = message.decode()
            if message.topic == TF and message.typename == TF_TYPE:
                for tf in msg.transforms:
                    pair = (tf.header.frame_id.lstrip("/"), tf.child_frame_id.lstrip("/"))
                    pose = _pose(tf.transform.translation, tf.transform.rotation)
                    if pair == (frames.map, frames.odom):
                        m2o.append((_stamp(tf.header), pose))
                    elif pair == (frames.odom, frames.base):
                        o2b.append((_stamp(tf.header), pose))
            elif message.topic == map_topic:
                t = _stamp(msg.header)
                if grid is None or t >= grid[0]:
                    grid = (t, msg)
            elif message.topic in (odom_topic, truth_topic):
                kept = odom if message.topic == odom_topic else truth
                kept.append((_stamp(msg.header), _pose(msg.pose.pose.position, msg.pose.pose.orientation)))
    odom_to_base = _sorted(o2b)
    return SlamLog(
        map_to_odom=_sorted(m2o),
        odom_to_base=odom_to_base,
        odometry=_sorted(odom) if odom else odom_to_base,
        truth=_sorted(truth),
        grid=None if grid is None else grid_of(grid[1]),
        scans=scans,
    )


def placed(track: Track, frame: Pose2D) -> Track:
    """``track`` moved by ``frame`` (each pose ``frame o pose``)."""
    out = Track()
    for t, pose in zip(track.stamps, track.poses, strict=True):
        out.add(t, compose(frame, pose))
    return out


def score_slam_logs(
    paths: Sequence[str | Path],
    out: Path,
    *,
    world: Any = None,
    grid: OccupancyGrid | None = None,
    map_pose: Pose2D | None = None,
    frames: Frames | None = None,
    plot: bool = True,
) -> MappingResult:
    """Score the SLAM run in the logs at ``paths`` and write ``omnibot map``'s outputs to ``out``:
    ``grid`` (a map file's) instead of the logs' last ``/map``; ``map_pose`` the map frame's pose in
    the truth's (world's) frame (default: see the module docstring). ConfigError, naming what is
    missing, for logs without the SLAM's ``map -> odom``, odometry or a map."""
    frames = frames or Frames()
    run = read_slam_logs(paths, frames=frames)
    if not len(run.map_to_odom):
        raise ConfigError(f"no {frames.map} -> {frames.odom} transform on {TF} in the logs: no SLAM estimate")
    if not len(run.odom_to_base):
        raise ConfigError(f"no {frames.odom} -> {frames.base} transform on {TF} in the logs: no odometry")
    grid = grid or run.grid
    if grid is None:
        raise ConfigError(f"no {MAP} (nav_msgs/OccupancyGrid) in the logs: give the map file with --map")
    estimate = run.estimate()
    tracks = {"estimate": estimate, "odometry": run.odometry}
    if len(run.truth):
        frame = map_pose if map_pose is not None else run.start_pose()
        tracks = {name: placed(track, frame) for name, track in tracks.items()}
        tracks["truth"] = run.truth
        grid = replace(grid, origin=compose(frame, grid.origin))
    elif world is not None:
        raise ConfigError(f"no truth ({TRUTH}) in the logs to place the map in the world: not with --world")
    report: dict[str, Any] = {
        "scans": run.scans,
        "corrections": len(run.map_to_odom),
        "distance_m": path_length(estimate.poses),
        "map_frame_in_world": None if not len(run.truth) else [frame.x, frame.y, frame.theta],
    }
    out.mkdir(parents=True, exist_ok=True)
    return write_report(out, grid, tracks, report, world=world, plot=plot)


__all__ = ["Frames", "SlamLog", "grid_of", "log_files", "placed", "read_slam_logs", "score_slam_logs"]
