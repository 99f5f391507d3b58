"""``omnibot map``: map a room with the robot's scanner while it is driven, and score the result.

::

    omnibot map [ROBOT OPTIONS] (--path PATH.csv | --teleop pad|keyboard | --explore) --out DIR
                [--scanner DEV] [--resolution M] [--duration S] [--speed V] [--follower NAME]
                [--ros2 [--namespace NS] [--frame-prefix P]]

The robot is driven as ``omnibot run`` drives it (a path follower, or a person with the deadman) on
one runtime, with the wheel-speed loop closed; a :class:`~omnibot.mapping.session.MappingSink` on
that runtime feeds every scan and the odometry to the SLAM. At the end ``DIR`` holds the map in
map_server's format (``map.yaml`` + ``map.pgm``), ``estimate.tum`` (the SLAM) and ``odometry.tum``
(wheels and gyro alone) and, on the simulator, ``truth.tum``, ``report.json`` (APE/RPE of both
against the truth, the map's precision and recall against the world) and ``map.png``.

On the simulator (no ``--port``, or ``--port sim://...``) the scans come from the simulated scanner
in lockstep with the physics; on a real robot (``--port /dev/ttyUSB0``, or the pty of ``omnibot sim
--pty``) from an RPLIDAR on ``--scanner``. The scanner is the runtime's (``Runtime.scanner``), so a
``--log`` records its scans on ``/scan`` (and the map and ``map -> odom`` at the end), and ``--ros2``
adds the ROS 2 bridge (as ``omnibot run --ros2``: paced to the wall clock, ``scan``, ``cmd_vel``...)
with the SLAM's ``map`` and ``map -> odom`` (:mod:`omnibot.ros2.mapping`). Exit status 0 when the map was written (and a path was
followed to its end), 1 when the run ended without a map or the follow was not completed, 2 for bad
options.
"""

from __future__ import annotations

import argparse
import contextlib
import math
import sys
from dataclasses import replace
from pathlib import Path
from typing import Any

from omnibot.errors import ConfigError

EXPLORE_LIMIT = 300.0
"""s ``--explore`` drives at most without ``--duration``."""
TRUTH_PERIOD = 0.01
"""Sampling of the simulator's true pose, s (the trajectories are associated within 10 ms)."""


def _add_drive_options(p: argparse.ArgumentParser) -> None:
    """How ``omnibot map`` drives: ``--path`` (its follower and ``--off-path``), ``--teleop`` or
    ``--explore``."""
    from omnibot.cliargs import add_off_path_option

    drive = p.add_mutually_exclusive_group(required=True)
    drive.add_argument("--path", metavar="PATH.csv", help="follow this path file while mapping")
    drive.add_argument(
        "--teleop", choices=("pad", "keyboard"), help="drive with a gamepad or this terminal's keys (deadman)"
    )
    drive.add_argument(
        "--explore",
        action="store_true",
        help="the robot drives itself to the edges of what it has mapped (frontiers) until the reachable "
        "space is mapped or --duration passes (default 300 s)",
    )
    p.add_argument("--follower", default="tracker", help="--path: seed002, pure_pursuit or tracker (default)")
    add_off_path_option(p, "--path: ")


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Declare ``omnibot map``'s options."""
    from omnibot.apps.ros2 import add_bridge_options
    from omnibot.cliargs import add_calibration_option, add_robot_options, add_wheel_loop_option

    add_robot_options(p, world="room", port_help="the simulated --robot in lockstep (paced with --teleop)")
    _add_drive_options(p)
    p.add_argument(
        "--out", metavar="DIR", required=True, help="directory for the map, trajectories and report"
    )
    p.add_argument(
        "--scanner",
        metavar="DEV",
        help="the RPLIDAR's serial port on a real robot (or the scanner pty of omnibot sim --pty)",
    )
    p.add_argument(
        "--resolution", type=float, default=0.05, metavar="M", help="map cell size, m (default 0.05)"
    )
    p.add_argument(
        "--hit-range",
        type=float,
        metavar="M",
        help="returns up to this range mark map cells, farther ones only clear (default: where the "
        "scanner's range noise reaches 2 cm, 2 m for an RPLIDAR A1)",
    )
    p.add_argument(
        "--speed",
        type=float,
        help="speed cap, m/s (default: --path the robot's limit; --explore 4 cm per scanner revolution, "
        "0.4 m/s at 10 Hz)",
    )
    p.add_argument("--config", metavar="FILE.yaml", help="--teleop parameters (default seed 003's)")
    p.add_argument(
        "--duration",
        type=float,
        metavar="S",
        help="stop after S seconds (default: the path's end, or Ctrl-C)",
    )
    add_wheel_loop_option(p)
    add_calibration_option(p)
    p.add_argument(
        "--ros2",
        action="store_true",
        help="publish on ROS 2 too (paced to the wall clock): scan, map, map -> odom, odom, tf..., "
        "and take cmd_vel (priority 90)",
    )
    add_bridge_options(p, scanner=False)
    p.set_defaults(dashboard=False, follow=None)


def _say(text: str) -> None:
    print(f"map: {text}", flush=True)


def _check(args: argparse.Namespace) -> Path:
    from omnibot.apps.ros2 import check as check_ros2
    from omnibot.cliargs import off_path_options, output_dir, simulated

    check_ros2(args)
    off_path_options(args)  # checked before anything starts
    if not (math.isfinite(args.resolution) and 0.005 <= args.resolution <= 1.0):
        raise ConfigError(f"expected a cell size of 0.005 to 1 m, got {args.resolution}", key="--resolution")
    if args.duration is not None and not (math.isfinite(args.duration) and args.duration > 0):
        raise ConfigError(f"expected a positive number of seconds, got {args.duration}", key="--duration")
    if args.hit_range is not None and not (math.isfinite(args.hit_range) and args.hit_range > 0):
        raise ConfigError(f"expected a positive range in m, got {args.hit_range}", key="--hit-range")
    if args.speed is not None and not (math.isfinite(args.speed) and args.speed > 0):
        raise ConfigError(f"expected a positive speed in m/s, got {args.speed}", key="--speed")
    if args.scanner is not None and simulated(args):
        raise ConfigError(
            "the simulated robot's scanner is simulated: --scanner goes with --port", key="--scanner"
        )
    return output_dir(args.out)


def run(args: argparse.Namespace) -> int:
    """``omnibot map``: drive, map, write the outputs; the exit status."""
    try:
        import gtsam  # noqa: F401  (the pose graph: the slam extra)
        import scipy  # noqa: F401
    except ImportError:
        raise ConfigError("omnibot map needs the slam extra: pip install 'omnibot[slam]'") from None
    from omnibot.apps.run import Parts, run_in_this_thread
    from omnibot.cliargs import check_sim_options, placed_by, sim_url
    from omnibot.control import read_path
    from omnibot.teleop import load_teleop_config

    out = _check(args)
    check_sim_options(args)
    config = load_teleop_config(args.config)
    try:
        path = read_path(args.path) if args.path else None
    except (OSError, ValueError) as exc:
        raise ConfigError(f"cannot read {args.path}: {exc}", key="--path") from None
    url = sim_url(args)
    if args.explore:
        return _explore(args, url, out)
    if path is not None and args.port is None:
        x, y, theta = path.start
        url += f"&pose={x:.4f},{y:.4f},{math.degrees(theta):.3f}"  # the robot stands at the path's start
    args.follow = args.path
    mapping = _Mapping(args)
    parts: Parts | None = None
    try:
        parts = run_in_this_thread(args, url, config, path, mapping.attach, _say, frame=mapping.map_to_odom)
    except ConfigError as exc:
        if args.port is not None:
            raise
        raise placed_by(
            exc, "--path", f"the first pose of {args.path}; give a path that starts inside the world"
        ) from None
    finally:
        mapping.close()
    return mapping.finish(out, parts, args.resolution)


def _explore(args: argparse.Namespace, url: str, out: Path) -> int:
    """``--explore``: the robot goes to the map's frontiers by itself (:mod:`omnibot.navigation.explore`)."""
    from omnibot.cliargs import recording_of, use_calibration
    from omnibot.client import robot_session
    from omnibot.motion import Pose2D
    from omnibot.navigation import navigation_runtime
    from omnibot.navigation.explore import GOTO, explore
    from omnibot.navigation.views import VIEW_SHARE
    from omnibot.transport import find_simulator

    mapping = _Mapping(args)
    limit = args.duration if args.duration is not None else EXPLORE_LIMIT
    try:
        with robot_session(url, args.robot, recording=recording_of(args)) as session:
            client, robot = session.client, session.robot
            sim = find_simulator(client.link)
            start = sim.pose if sim is not None else Pose2D(0.0, 0.0, 0.0)
            slip = use_calibration(args, client, robot)
            with navigation_runtime(client, robot, start, slip=slip, recording=recording_of(args)) as runtime:
                mapping.attach(runtime, session, estimator=False)
                sink = mapping.sink
                _say(f"exploring for at most {limit:g} s")
                snapshots: list[Any] = []

                def grid_now() -> Any:
                    snapshots[:] = [sink.snapshot()]
                    return snapshots[0](args.resolution, mapping.noise)

                def returns_now(grid: Any) -> Any:  # the returns of the snapshot that map was made of
                    return snapshots[0].returns(grid)

                result = explore(
                    runtime,
                    robot,
                    grid_now,
                    sink.pose_now,
                    scan=sink.points_now,
                    returns=returns_now,
                    time_limit=limit,
                    options=replace(GOTO, speed=args.speed),
                    view_range=VIEW_SHARE * mapping.noise.hit_range,
                    say=_say,
                )
            _say(f"exploring ended: {result.summary()}")
    finally:
        mapping.close()
    return mapping.finish(out, None, args.resolution)  # the map written: 0, however exploring ended


class _Mapping:
    """The mapping sink and the simulator's truth of one run, attached to its runtime."""

    def __init__(self, args: argparse.Namespace) -> None:
        self.args = args
        self.sink: Any = None
        self.truth: Any = None
        self.world: Any = None
        self._sim: Any = None
        self._listener: Any = None
        self.noise: Any = None
        self.scans: Any = None
        self.runtime: Any = None

    def map_to_odom(self) -> Any:
        """The SLAM's ``map -> odom`` now (None before its first keyframe, or before the sink): a
        path is followed in the map's frame, on the SLAM's pose, not on the drifting odometry."""
        return None if self.sink is None else self.sink.map_to_odom_now()

    def attach(self, runtime: Any, session: Any, *, estimator: bool = True) -> list[Any]:
        from omnibot.estimation import make_estimator
        from omnibot.lidar import open_scanner
        from omnibot.mapping import MappingSink, RangeNoise, Track
        from omnibot.motion import Pose2D
        from omnibot.transport import find_simulator

        client, robot = session.client, session.robot
        scans = open_scanner(self.args.scanner, client.link, robot)
        self.noise = RangeNoise.of(robot, self.args.hit_range)
        sim = find_simulator(client.link)
        start = Pose2D(0.0, 0.0, 0.0)
        if sim is not None:
            self._sim = sim
            self.world = sim.world
            start = sim.pose  # the map frame is the world's: the estimate starts at the true pose
            self.truth = Track()
            truth = self.truth

            def record(snap: Any) -> None:
                truth.add(snap.t, snap.pose)

            self._listener = record
            sim.add_listener(record, TRUTH_PERIOD)
        if estimator:
            slip = runtime.slip.params if runtime.slip is not None else None
            runtime.estimator = make_estimator("fused", robot, start, slip)
        self.scans, self.runtime = scans, runtime
        runtime.scanner = scans  # one scanner, many readers: the SLAM, the log, ROS 2
        self.sink = MappingSink(None, threaded=sim is None)
        runtime.add_sink(self.sink)
        where = "the simulated scanner" if sim is not None else f"the scanner on {self.args.scanner}"
        _say(f"mapping with {where}; the SLAM corrects the wheel and gyro odometry")
        return self._ros2(runtime, robot) if self.args.ros2 else []

    def _ros2(self, runtime: Any, robot: Any) -> list[Any]:
        """The bridge on the runtime (omnibot run --ros2's), and the map publisher beside it."""
        from omnibot.apps.ros2 import attach_bridge
        from omnibot.ros2 import MapPublisher, Ros2Sink

        node = attach_bridge(runtime, robot, self.args)
        self.args.ros2_node = node  # compose attaches no second one
        bridge = next(s for s in runtime.sinks if isinstance(s, Ros2Sink))
        publisher = MapPublisher(bridge, self.sink, resolution=self.args.resolution, noise=self.noise)
        runtime.add_sink(publisher)
        return [node.close, publisher.close]

    def close(self) -> None:
        if self._sim is not None and self._listener is not None:
            self._sim.remove_listener(self._listener)
            self._listener = None
        if self.runtime is not None:
            self.runtime.scanner = None
        if self.sink is not None:
            self.sink.close()
        if self.scans is not None:
            with contextlib.suppress(Exception):
                self.scans.close()
            self.scans = None

    def finish(self, out: Path, parts: Any, resolution: float) -> int:
        from omnibot.apps.run import outcome
        from omnibot.mapping import score_lines, write_outputs
        from omnibot.outputs import made_directory

        sink = self.sink
        if sink is None:
            return 1
        if sink.failure is not None:
            print(f"omnibot map: the SLAM failed: {sink.failure}", file=sys.stderr)
            return 1
        try:
            result = write_outputs(
                made_directory(out, "--out"),
                sink,
                truth=self.truth,
                world=self.world,
                resolution=resolution,
                noise=self.noise,
            )
        except ValueError as exc:
            print(f"omnibot map: {exc} ({sink.received} scans received)", file=sys.stderr)
            return 1
        self._log_map(result.grid)
        report = result.report
        _say(
            f"{report['scans']} scans, {report['keyframes']} keyframes, {report['loop_closures']} loop closures, "
            f"{report['distance_m']:.1f} m driven"
        )
        for line in score_lines(report):
            _say(line)
        _say(f"wrote {', '.join(str(f) for f in result.files)}")
        status = 0
        if parts is not None and parts.judge is not None:
            verdict = parts.judge.verdict()  # given at the follow's end (and said then), or now
            said = {n.text for n in parts.printer.seen} if parts.printer is not None else set()
            for line in outcome(verdict):
                if line not in said:
                    _say(line)
            status = 0 if verdict["completed"] else 1
        return status

    def _log_map(self, grid: Any) -> None:
        """The map and ``map -> odom`` on ``/map`` and ``/tf`` of the command's ``--log``, if any, at the
        last odometry time."""
        from omnibot.cliargs import recording_of

        recording = recording_of(self.args)
        recorder = recording.recorder if recording is not None else None
        sink = self.sink
        if recorder is None or grid is None or not sink.odometry.stamps:
            return
        recorder.map(grid, sink.odometry.stamps[-1], sink.slam.map_to_odom)
