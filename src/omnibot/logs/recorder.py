"""The MCAP recorder: a plain object the client hands what happens to (and, on a runtime, its sink: :mod:`omnibot.logs.sink`).

::

    rec = Recorder("run.mcap")                 # ros2 profile, zstd chunks, rosbag2's metadata
    rec.attach(client, robot)                  # the client's byte trace, messages and events
    ...                                        # the run
    rec.close()                                # summary + rosbag2 metadata (a killed run keeps
                                               # every chunk written before it died)

What is called, and what it writes (topic, type; every time on the link clock, mapped onto the wall
clock of the moment recording started):

* :meth:`link_bytes` (the client's byte trace, as ``spy+`` sees it): ``/omnibot/link``
  ``omnibot_msgs/msg/LinkBytes``;
* :meth:`message` (each command sent, reply matched; events come through :meth:`event`, a client
  listener): ``/omnibot/protocol`` ``omnibot_msgs/msg/ProtocolLine``; a VEL also as ``cmd_vel``
  ``geometry_msgs/msg/TwistStamped``;
* a telemetry event: ``joint_states`` (wheel joints of the URDF: angle, speed, and the motor power
  in PWM counts as effort), ``imu`` (gyro rate, heading as orientation), ``range/<sonar>`` per sonar,
  the estimate (the ``estimator`` named, run on each sample) as ``odom`` and ``/tf`` odom ->
  base_link (and exactly, heading unwrapped, as ``/omnibot/estimate`` geometry_msgs/Pose2D, which
  ``omnibot log replay`` compares with), and the simulator's truth as ``/omnibot/truth`` when the link is an in-process one;
* a ``RANGE`` event (a sonar pinged by ``SONAR``): ``range/<sonar>``, as a TEL sample's ranges;
* :meth:`scan` (a runtime's scanner, :mod:`omnibot.logs.sink`): ``/scan`` ``sensor_msgs/msg/LaserScan``
  (:func:`laser_scan`), stamped at the scan's first ray; ``/map`` ``nav_msgs/msg/OccupancyGrid``
  (:func:`occupancy_grid`) and ``/tf`` map -> odom (:func:`map_to_odom`) are written by ``omnibot
  map`` at its end;
* :meth:`start`: ``robot_description`` (the URDF) and ``calibration`` (the description's calibration
  tables, YAML), both ``std_msgs/msg/String``, and the MCAP metadata ``omnibot`` that ``omnibot log
  replay`` needs (the description, the estimator, the start pose).

The file itself (chunks, channels, rosbag2's metadata, a failed write) is :class:`LogWriter`'s
(:mod:`omnibot.logs.writer`); the messages are built by :mod:`omnibot.logs.rosmsg`.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from omnibot import __version__
from omnibot.client import Event, RangeEvent, RobotClient, Telemetry
from omnibot.errors import ConfigError
from omnibot.estimation import Estimator, make_estimator
from omnibot.logs import schemas
from omnibot.logs.rosmsg import (
    POSE_VARIANCE,
    TWIST_VARIANCE,
    header,
    imu,
    laser_scan,
    map_to_odom,
    occupancy_grid,
    odometry,
    sonar_range,
    stamp,
    twist,
)
from omnibot.logs.topics import (
    ADOPTED,
    CALIBRATION,
    CMD_VEL,
    DEFAULT_ESTIMATOR,
    ESTIMATE,
    IMU,
    JOINT_STATES,
    LINK,
    MAP,
    ODOM,
    PROTOCOL,
    ROBOT_DESCRIPTION,
    SCAN,
    TF,
    TRUTH,
    range_topic,
)
from omnibot.logs.writer import CHUNK_SIZE, FLUSH_PERIOD, LogWriter, Mirror
from omnibot.motion import Estimate, Pose2D
from omnibot.protocol import text
from omnibot.protocol.messages import Malformed, Message, Vel
from omnibot.robot import RobotDescription, load_robot, preset_names
from omnibot.robot.kinematics import world_to_body
from omnibot.scan import Scan

log = logging.getLogger("omnibot.logs")


class Recorder(LogWriter):
    """Records a run into one MCAP file (``path``; None: no file) and hands every message to
    ``mirrors`` (``mirror(topic, typename, cdr_bytes, ns)``: the Foxglove live server); see the module
    docstring for what each method records."""

    def __init__(
        self,
        path: str | Path | None,
        *,
        estimator: str = DEFAULT_ESTIMATOR,
        chunk_size: int = CHUNK_SIZE,
        flush_period: float = FLUSH_PERIOD,
        compression: str = "zstd",
        mirrors: Sequence[Mirror] = (),
    ) -> None:
        super().__init__(
            path, chunk_size=chunk_size, flush_period=flush_period, compression=compression, mirrors=mirrors
        )
        self.estimator_name = estimator
        self.robot: RobotDescription | None = None
        self.estimator: Estimator | None = None
        self._simulator: Any = None
        self._joints: list[str] = []
        self._cpr: list[float] = []
        self._last_tel: tuple[float, tuple[int, ...]] | None = None
        self._clients: list[RobotClient] = []
        self.samples = 0
        """Telemetry samples with encoders seen (what an estimator is fed)."""
        self.last_sample: Telemetry | None = None

    # ------------------------------------------------------------------ the run's context

    def start(self, robot: RobotDescription, *, simulator: Any = None, url: str = "", t: float = 0.0) -> None:
        """The robot (URDF, calibration, estimator) and, on an in-process link, its simulator."""
        from omnibot.robot import to_urdf

        self.robot = robot
        self._simulator = simulator
        self._joints = [f"{w.name}_joint" for w in robot.wheels]
        cpr = {m.wheel: m.counts_per_rev for m in robot.encoders.motors}
        self._cpr = [float(cpr.get(w.name, 0)) for w in robot.wheels]
        try:
            self.estimator = make_estimator(self.estimator_name, robot)
        except ConfigError as exc:
            log.warning("no estimate in the log: %s", exc)
        ns = self.ns(t)
        self.write(
            ROBOT_DESCRIPTION,
            "std_msgs/msg/String",
            schemas.new("std_msgs/msg/String", data=to_urdf(robot)),
            ns,
        )
        if robot.calibration is not None:
            cal = yaml.safe_dump(
                robot.calibration.model_dump(mode="json", exclude_none=True), sort_keys=False
            )
            self.write(CALIBRATION, "std_msgs/msg/String", schemas.new("std_msgs/msg/String", data=cal), ns)
        description = yaml.safe_dump(robot.model_dump(mode="json", exclude_none=True), sort_keys=False)
        if self._writer is None:
            return
        self.add_metadata(
            "omnibot",
            {
                "version": __version__,
                "robot": robot.name,
                "url": url,
                "estimator": self.estimator_name if self.estimator is not None else "",
                "description": description,
            },
        )

    def attach(
        self, client: RobotClient, robot: RobotDescription | None = None, *, guess: bool = False
    ) -> None:
        """Record what ``client`` sends, receives and decodes (once per client); ``robot`` starts the
        recording's context (:meth:`start`) if it has none yet. ``guess``: without ``robot``, take
        the preset the controller's HELLO names (else no URDF, no estimate)."""
        from omnibot.transport import find_simulator

        if not any(c is client for c in self._clients):
            self._clients.append(client)
            client.add_tracer(self)
            client.add_listener(self.event)
            if self._t0 is not None:
                # another link (calibrate: a fresh simulated robot per floor, its clock from 0 again):
                # its time goes on from the last message, so the log's time never runs backwards
                self._epoch_ns, self._t0 = self._last_ns, client.clock.now()
            if self.robot is not None:
                self._simulator = find_simulator(client.link)
        if self.robot is not None:
            return
        hello = client.last_hello
        if robot is None and guess and hello is not None and hello.name in preset_names():
            robot = load_robot(hello.name)
        if robot is not None:
            self.start(
                robot, simulator=find_simulator(client.link), url=client.link.url, t=client.clock.now()
            )

    def detach(self, client: RobotClient) -> None:
        """Stop recording ``client``."""
        client.remove_tracer(self)
        client.remove_listener(self.event)
        self._clients = [c for c in self._clients if c is not client]

    # ------------------------------------------------------------------ what the client reports

    def link_bytes(self, t: float, kind: str, data: bytes = b"", note: str = "") -> None:
        """Bytes on the link: ``TX`` written, ``RX`` read, ``ERR`` a failure, ``CLOSE``."""
        ns = self.ns(t)
        msg = schemas.new(
            schemas.LINK_BYTES,
            stamp=stamp(ns),
            kind=kind,
            data=np.frombuffer(data, dtype=np.uint8),
            note=note,
        )
        self.write(LINK, schemas.LINK_BYTES, msg, ns)

    def message(self, t: float, direction: str, message: Message | Malformed) -> None:
        """A decoded protocol message: ``command`` sent, ``reply`` matched, ``event``."""
        ns = self.ns(t)
        if isinstance(message, Malformed):
            keyword, line = "MALFORMED", f"{message.reason}: {message.raw!r}"
        else:
            keyword, line = message.keyword, text.encode(message).decode("ascii", "replace").strip()
        msg = schemas.new(
            schemas.PROTOCOL_LINE, stamp=stamp(ns), direction=direction, keyword=keyword, text=line
        )
        self.write(PROTOCOL, schemas.PROTOCOL_LINE, msg, ns)
        if direction == "command" and isinstance(message, Vel):
            cmd = twist(message.vx / 100, message.vy / 100, math.radians(message.w))
            stamped = schemas.new("geometry_msgs/msg/TwistStamped", header=header(ns, "base_link"), twist=cmd)
            self.write(CMD_VEL, "geometry_msgs/msg/TwistStamped", stamped, ns)

    def event(self, event: Event) -> None:
        """A client listener: every event as a protocol line, telemetry and ranges as ROS messages too."""
        if event.message is not None:
            self.message(event.time, "event", event.message)
        if isinstance(event, Telemetry):
            self.telemetry(event)
        elif isinstance(event, RangeEvent) and self.robot is not None:
            sonars = self.robot.sonars
            if 1 <= event.sonar <= len(sonars):  # numbered 1..k as in the protocol
                ns = self.ns(event.time)
                sonar = sonars[event.sonar - 1]
                self.write(
                    range_topic(sonar.name),
                    "sensor_msgs/msg/Range",
                    sonar_range(ns, sonar, event.distance),
                    ns,
                )

    def telemetry(self, tel: Telemetry) -> None:
        """Record a TEL sample: joint states, IMU, sonar ranges, the estimator's odometry and pose, and
        the simulator's truth when there is one."""
        ns = self.ns(tel.time)
        if tel.encoders is not None and self._joints and len(tel.encoders) == len(self._joints):
            self._joint_states(ns, tel)
        if tel.gyro_rate is not None or tel.heading is not None:
            self.write(IMU, "sensor_msgs/msg/Imu", imu(ns, tel), ns)
        if tel.ranges is not None and self.robot is not None:
            for sonar, distance in zip(self.robot.sonars, tel.ranges, strict=False):
                self.write(
                    range_topic(sonar.name), "sensor_msgs/msg/Range", sonar_range(ns, sonar, distance), ns
                )
        if tel.encoders is not None:
            self.samples += 1
            self.last_sample = tel
            if self.estimator is not None:
                self.estimate(tel.time, self.estimator.update(tel))
        if self._simulator is not None:
            pose, vel = self._simulator.pose, self._simulator.twist
            self.write_pose(TRUTH, ns, Pose2D(pose.x, pose.y, pose.theta), (vel.vx, vel.vy, vel.w))

    def truth_rows(self, rows: Sequence[tuple[float, float, float, float]]) -> int:
        """Ground truth recorded elsewhere (rows ``t, x, y, theta``, ``t`` on the link's clock: the pty
        emulator's ``--truth`` file placed by :class:`omnibot.demos.truth.ControllerClock`) on
        ``/omnibot/truth``, the body twist from the poses either side. Returns the rows written (none
        before the recording has its robot)."""
        if self.robot is None:
            return 0
        for k, (t, x, y, theta) in enumerate(rows):
            before, after = rows[max(k - 1, 0)], rows[min(k + 1, len(rows) - 1)]
            dt = after[0] - before[0]
            world = (
                ((after[1] - before[1]) / dt, (after[2] - before[2]) / dt, (after[3] - before[3]) / dt)
                if dt > 0
                else (0.0, 0.0, 0.0)
            )
            vx, vy, w = (float(v) for v in world_to_body(world, theta))
            self.write_pose(TRUTH, self.ns(t), Pose2D(x, y, theta), (vx, vy, w))
        return len(rows)

    def estimate(self, t: float, est: Estimate) -> None:
        """An estimate at link time ``t``: ``odom``, ``/tf`` odom -> base_link, ``/omnibot/estimate``."""
        ns = self.ns(t)
        body = world_to_body((est.vx, est.vy, est.w), est.theta)
        pose = Pose2D(est.x, est.y, est.theta)
        body3 = (float(body[0]), float(body[1]), est.w)
        self.write_pose(ODOM, ns, pose, body3, tf=True, variances=(POSE_VARIANCE, TWIST_VARIANCE))
        pose2d = schemas.new("geometry_msgs/msg/Pose2D", x=est.x, y=est.y, theta=est.theta)
        self.write(ESTIMATE, "geometry_msgs/msg/Pose2D", pose2d, ns)

    def scan(self, scan: Scan) -> None:
        """A scanner's revolution on ``/scan`` (sensor_msgs/LaserScan), stamped at its first ray."""
        ns = self.ns(scan.stamp)
        self.write(SCAN, "sensor_msgs/msg/LaserScan", laser_scan(scan, ns), ns)

    def map(self, grid: Any, t: float, odom: Pose2D) -> None:
        """A SLAM's result at link time ``t``: the map on ``/map`` and ``odom``, the odometry frame's pose
        in the map frame, as ``/tf`` map -> odom."""
        ns = self.ns(t)
        self.write(MAP, "nav_msgs/msg/OccupancyGrid", occupancy_grid(grid, ns), ns)
        self.write(TF, "tf2_msgs/msg/TFMessage", map_to_odom(odom, ns), ns)

    def adopt(self, name: str, start: Pose2D, *, before: Telemetry | None = None, slip: bool = False) -> None:
        """From now on the estimate is another's (a runtime's: the one a follower steers by), handed
        in with :meth:`estimate` after each sample, from ``before`` on (the sample about to be
        folded in, None: the next); the recorder's own estimator stops. The MCAP metadata
        ``omnibot_estimator`` tells ``log replay`` how to reproduce it: its ``name``, the ``start``
        pose, the telemetry ``samples`` (with encoders) and ``estimates`` recorded before (which it
        skips), and whether a floor's ``slip`` correction was on (not in the log: no exact replay)."""
        self.estimator = None
        samples = self.samples - (1 if before is not None and before is self.last_sample else 0)
        if self._writer is None or self.closed:
            return
        self.add_metadata(
            ADOPTED,
            {
                "name": name,
                "start": f"{start.x!r} {start.y!r} {start.theta!r}",
                "samples": str(samples),
                "estimates": str(self.counts[ESTIMATE]),
                "slip": "yes" if slip else "",
            },
        )

    def write_pose(
        self,
        topic: str,
        ns: int,
        pose: Pose2D,
        body: tuple[float, float, float],
        *,
        tf: bool = False,
        variances: tuple[Sequence[float], Sequence[float]] | None = None,
    ) -> None:
        """An Odometry odom -> base_link on ``topic`` (with ``variances``, the pose's and the twist's,
        on its covariances; zero without) and the transform on ``/tf`` if ``tf``."""
        msg = odometry(ns, "odom", "base_link", pose, body, variances)
        self.write(topic, "nav_msgs/msg/Odometry", msg, ns)
        if tf:
            self.write(TF, "tf2_msgs/msg/TFMessage", map_to_odom(pose, ns, "odom", "base_link"), ns)

    def _joint_states(self, ns: int, tel: Telemetry) -> None:
        assert tel.encoders is not None
        angles = [
            2 * math.pi * c / cpr if cpr else 0.0 for c, cpr in zip(tel.encoders, self._cpr, strict=True)
        ]
        speeds = [0.0] * len(angles)
        if self._last_tel is not None:
            t_prev, prev = self._last_tel
            dt = tel.controller_time - t_prev
            if dt > 0:
                speeds = [
                    2 * math.pi * (c - p) / cpr / dt if cpr else 0.0
                    for c, p, cpr in zip(tel.encoders, prev, self._cpr, strict=True)
                ]
        self._last_tel = (tel.controller_time, tel.encoders)
        effort = [float(p) for p in tel.powers] if tel.powers is not None else []
        msg = schemas.new(
            "sensor_msgs/msg/JointState",
            header=header(ns, "base_link"),
            name=list(self._joints),
            position=np.array(angles, dtype=np.float64),
            velocity=np.array(speeds, dtype=np.float64),
            effort=np.array(effort, dtype=np.float64),
        )
        self.write(JOINT_STATES, "sensor_msgs/msg/JointState", msg, ns)

    # ------------------------------------------------------------------ the end

    def close(self) -> None:
        """Detach, write the open chunk, rosbag2's metadata and the summary; close the file."""
        if self.closed:
            return
        for client in list(self._clients):
            self.detach(client)
        super().close()
