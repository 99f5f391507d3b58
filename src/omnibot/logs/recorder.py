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

Bounded memory: messages go to the current chunk, which is compressed and written when it reaches
``chunk_size`` bytes or is ``flush_period`` s (wall clock) old; only the chunk indexes (one per chunk)
stay in memory. The file is written unbuffered, so a SIGKILL loses only the open chunk.

A write that fails (a full disk, ``ulimit -f``, a read-only or failing device: any ``OSError``) stops
the file, never the run: the recorder says so once (a warning on stderr and to every
:attr:`Recorder.on_failure` callback: a runtime's notice), keeps what it wrote before (``omnibot log
recover`` rewrites it whole), writes nothing more to it and raises nothing into the client's
listeners or the runtime's loop; :attr:`Recorder.failure` tells the command its log is incomplete.
"""

from __future__ import annotations

import contextlib
import logging
import math
import sys
import threading
import time
from collections import Counter
from collections.abc import Callable, Iterator, Mapping, Sequence
from pathlib import Path
from typing import IO, Any, Protocol, cast

import numpy as np
import yaml
from mcap.writer import CompressionType, Writer

from omnibot import __version__
from omnibot.client import Event, RangeEvent, RobotClient, Telemetry
from omnibot.config_errors import load_yaml
from omnibot.errors import ConfigError
from omnibot.estimation import Estimator, make_estimator
from omnibot.logs import schemas
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
from omnibot.motion import Estimate, Pose2D
from omnibot.protocol import text
from omnibot.protocol.messages import Malformed, Message, Vel
from omnibot.robot import RobotDescription, load_robot, preset_names
from omnibot.robot.kinematics import world_to_body
from omnibot.scan import Scan
from omnibot.signals import held

log = logging.getLogger("omnibot.logs")

CHUNK_SIZE = 256 * 1024
"""Uncompressed bytes after which a chunk is compressed and written."""
FLUSH_PERIOD = 1.0
"""Wall-clock seconds after which an open chunk is written anyway (what a SIGKILL can lose)."""

_QOS_VOLATILE = (
    "- history: keep_last\n  depth: 10\n  reliability: reliable\n  durability: volatile\n"
    "  deadline: {sec: 0, nsec: 0}\n  lifespan: {sec: 0, nsec: 0}\n  liveliness: automatic\n"
    "  liveliness_lease_duration: {sec: 0, nsec: 0}\n  avoid_ros_namespace_conventions: false\n"
)
_QOS_LATCHED = _QOS_VOLATILE.replace("depth: 10", "depth: 1").replace("volatile", "transient_local")
_LATCHED = {ROBOT_DESCRIPTION, CALIBRATION, MAP}


def stamp(ns: int) -> Any:
    """A builtin_interfaces/Time for ``ns`` nanoseconds since the epoch."""
    return schemas.new("builtin_interfaces/msg/Time", sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000)


def header(ns: int, frame: str) -> Any:
    """A ``std_msgs/Header`` stamped at ``ns`` in ``frame``."""
    return schemas.new("std_msgs/msg/Header", stamp=stamp(ns), frame_id=frame)


def quaternion(yaw: float) -> Any:
    """A ``geometry_msgs/Quaternion`` of a rotation by ``yaw`` rad about z."""
    return schemas.new("geometry_msgs/msg/Quaternion", x=0.0, y=0.0, z=math.sin(yaw / 2), w=math.cos(yaw / 2))


def vector(x: float = 0.0, y: float = 0.0, z: float = 0.0) -> Any:
    """A ``geometry_msgs/Vector3``."""
    return schemas.new("geometry_msgs/msg/Vector3", x=x, y=y, z=z)


def twist(vx: float, vy: float, w: float) -> Any:
    """A ``geometry_msgs/Twist``: ``vx``, ``vy`` m/s and ``w`` rad/s about z."""
    return schemas.new("geometry_msgs/msg/Twist", linear=vector(vx, vy), angular=vector(z=w))


def laser_scan(scan: Scan, ns: int) -> Any:
    """sensor_msgs/LaserScan of ``scan`` stamped at ``ns`` in its frame, field for field (a clockwise
    scanner's negative ``angle_increment`` as it is; ``angle_max`` the last ray's direction; ranges
    float32 with ``inf`` for no return, REP 117)."""
    n = len(scan)
    intensities: Any = scan.intensities if scan.intensities is not None else []
    return schemas.new(
        "sensor_msgs/msg/LaserScan",
        header=header(ns, scan.frame),
        angle_min=float(scan.angle_min),
        angle_max=float(scan.angle_min + scan.angle_increment * (n - 1)),
        angle_increment=float(scan.angle_increment),
        time_increment=float(scan.time_increment),
        scan_time=float(scan.scan_time),
        range_min=float(scan.range_min),
        range_max=float(scan.range_max),
        ranges=np.asarray(scan.ranges, dtype=np.float32),
        intensities=np.asarray(intensities, dtype=np.float32),
    )


def occupancy_grid(grid: Any, ns: int, frame: str = "map") -> Any:
    """nav_msgs/OccupancyGrid of an :class:`omnibot.mapping.grid.OccupancyGrid` (row 0, the bottom row,
    first; -1 unknown, 0..100 occupancy), stamped at ``ns`` in ``frame``."""
    rows, cols = grid.shape
    origin = grid.origin
    pose = schemas.new(
        "geometry_msgs/msg/Pose",
        position=schemas.new("geometry_msgs/msg/Point", x=float(origin.x), y=float(origin.y), z=0.0),
        orientation=quaternion(float(origin.theta)),
    )
    info = schemas.new(
        "nav_msgs/msg/MapMetaData",
        map_load_time=stamp(ns),
        resolution=float(grid.resolution),
        width=int(cols),
        height=int(rows),
        origin=pose,
    )
    data = np.ascontiguousarray(grid.data, dtype=np.int8).reshape(-1)
    return schemas.new("nav_msgs/msg/OccupancyGrid", header=header(ns, frame), info=info, data=data)


def map_to_odom(pose: Pose2D, ns: int, parent: str = "map", child: str = "odom") -> Any:
    """tf2_msgs/TFMessage with the one transform ``parent`` -> ``child`` (the SLAM's ``map -> odom``:
    the odometry frame's ``pose`` in the map frame)."""
    transform = schemas.new(
        "geometry_msgs/msg/TransformStamped",
        header=header(ns, parent),
        child_frame_id=child,
        transform=schemas.new(
            "geometry_msgs/msg/Transform",
            translation=vector(float(pose.x), float(pose.y)),
            rotation=quaternion(float(pose.theta)),
        ),
    )
    return schemas.new("tf2_msgs/msg/TFMessage", transforms=[transform])


POSE_VARIANCE = (1e-3, 1e-3, 1e6, 1e6, 1e6, 4e-3)
"""The estimate's pose variances (x, y, z, roll, pitch, yaw): a planar base's, large for what it
cannot observe (robot_localization's convention)."""
TWIST_VARIANCE = (1e-3, 1e-3, 1e6, 1e6, 1e6, 2e-3)


def covariance(variances: Sequence[float] | None) -> Any:
    """A 6x6 row-major covariance with ``variances`` on its diagonal (None: all zero, unknown)."""
    if variances is None:
        return np.zeros(36, dtype=np.float64)
    return np.diag(np.array(variances, dtype=np.float64)).reshape(36)


def odometry(
    ns: int,
    frame: str,
    child: str,
    pose: Pose2D,
    body: tuple[float, float, float],
    variances: tuple[Sequence[float], Sequence[float]] | None = None,
) -> Any:
    """nav_msgs/Odometry: ``pose`` in ``frame``, ``body`` twist (vx, vy, w) in ``child``; ``variances``
    (the pose's, the twist's) on the covariances' diagonals (None: zero)."""
    pose_var, twist_var = variances or (None, None)
    position = schemas.new("geometry_msgs/msg/Point", x=pose.x, y=pose.y, z=0.0)
    return schemas.new(
        "nav_msgs/msg/Odometry",
        header=header(ns, frame),
        child_frame_id=child,
        pose=schemas.new(
            "geometry_msgs/msg/PoseWithCovariance",
            pose=schemas.new("geometry_msgs/msg/Pose", position=position, orientation=quaternion(pose.theta)),
            covariance=covariance(pose_var),
        ),
        twist=schemas.new(
            "geometry_msgs/msg/TwistWithCovariance", twist=twist(*body), covariance=covariance(twist_var)
        ),
    )


def offered_qos(topic: str) -> str:
    """The ``offered_qos_profiles`` (rosbag2's YAML) of ``topic``: transient local for the URDF and
    the calibration (sent once), volatile for the rest."""
    return _QOS_LATCHED if topic in _LATCHED else _QOS_VOLATILE


def rosbag2_metadata(
    file_name: str, channels: Mapping[str, str], counts: Mapping[str, int], start_ns: int, end_ns: int
) -> str:
    """rosbag2's ``serialized_metadata`` (its ``metadata.yaml``) of one MCAP file ``file_name`` with
    ``channels`` (topic -> type), ``counts`` messages per topic, from ``start_ns`` to ``end_ns``."""
    duration = max(0, end_ns - start_ns)
    total = sum(counts.get(topic, 0) for topic in channels)
    topics = [
        {
            "topic_metadata": {
                "name": topic,
                "type": typename,
                "serialization_format": "cdr",
                "offered_qos_profiles": load_yaml(offered_qos(topic)),
                "type_description_hash": schemas.type_hash(typename),
            },
            "message_count": counts.get(topic, 0),
        }
        for topic, typename in channels.items()
    ]
    info = {
        "rosbag2_bagfile_information": {
            "version": 9,
            "storage_identifier": "mcap",
            "relative_file_paths": [file_name],
            "duration": {"nanoseconds": duration},
            "starting_time": {"nanoseconds_since_epoch": start_ns},
            "message_count": total,
            "topics_with_message_count": topics,
            "compression_format": "",
            "compression_mode": "",
            "files": [
                {
                    "path": file_name,
                    "starting_time": {"nanoseconds_since_epoch": start_ns},
                    "duration": {"nanoseconds": duration},
                    "message_count": total,
                }
            ],
            "custom_data": {"omnibot_version": __version__},
            "ros_distro": "jazzy",
        }
    }
    return yaml.safe_dump(info, sort_keys=False)


class Mirror(Protocol):
    """Something that gets every message the recorder writes (the Foxglove live server)."""

    def __call__(self, topic: str, typename: str, data: bytes, ns: int) -> None:
        """Take one message: its ``topic``, ``typename``, CDR ``data`` and time ``ns``."""

    def close(self) -> None:
        """Release what the mirror holds (a server, channels)."""


class _Direct:
    """A file the MCAP writer writes straight to the OS (no user-space buffer a SIGKILL would lose;
    the writer already hands over whole chunks)."""

    def __init__(self, raw: IO[bytes]) -> None:
        self._raw = raw
        self._pos = 0

    def write(self, data: bytes | memoryview) -> int:
        view = memoryview(data)
        while view:
            n = self._raw.write(view)
            view = view[n or 0 :]
        self._pos += len(data)
        return len(data)

    def tell(self) -> int:
        return self._pos

    def flush(self) -> None:
        pass


def _start_file(path: Path, chunk_size: int, compression: str) -> tuple[IO[bytes], Writer]:
    """``path`` opened (its folder made) and an MCAP writer started on it, its header written; a
    :class:`ConfigError` for ``--log`` when it cannot be."""
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        file = open(path, "wb", buffering=0)  # noqa: SIM115 (the recorder closes it in close())
    except OSError as exc:
        raise ConfigError(f"cannot write {path}: {exc.strerror or exc}", key="--log") from None
    kinds = {"zstd": CompressionType.ZSTD, "lz4": CompressionType.LZ4, "none": CompressionType.NONE}
    writer = Writer(cast("IO[Any]", _Direct(file)), chunk_size=chunk_size, compression=kinds[compression])
    try:
        writer.start(profile="ros2", library=f"omnibot {__version__}")
    except OSError as exc:  # no room for the header: the command cannot start
        file.close()
        raise ConfigError(f"cannot write {path}: {exc.strerror or exc}", key="--log") from None
    return file, writer


class Recorder:
    """Writes one MCAP file (``path``; None: no file) and hands every message to ``mirrors``
    (``mirror(topic, typename, cdr_bytes, ns)``: the Foxglove live server); see the module docstring
    for what each method records."""

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
        self.path = Path(path) if path is not None else None
        self.mirrors = list(mirrors)
        self._file: IO[bytes] | None = None
        self._writer: Writer | None = None
        if self.path is not None:
            self._file, self._writer = _start_file(self.path, chunk_size, compression)
        self.compression = compression
        self.estimator_name = estimator
        self.flush_period = flush_period
        self._schemas: dict[str, int] = {}
        self._channels: dict[str, tuple[int, str]] = {}
        self.counts: Counter[str] = Counter()
        """Messages written per topic."""
        self.lost = 0
        """Messages that could not be serialized (a bug; logged): 0 in a good run."""
        self._epoch_ns = time.time_ns()
        self._t0: float | None = None
        self._first_ns: int | None = None
        self._last_ns = 0
        self._last_flush = time.monotonic()
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
        self.closed = False
        self.failure: str | None = None
        """Why the file stopped being written mid-run (a write failed: a full disk...); None while
        it is whole."""
        self.on_failure: list[Callable[[str], None]] = []
        """Called once with the warning when a write fails (any thread; a runtime's notice)."""
        self._fail_lock = threading.Lock()
        self._lock = threading.RLock()
        """Held around every use of the MCAP writer: its records are several writes each, and a
        recorder is not bound to one thread (front ends' callbacks, a close at a signal)."""

    # ------------------------------------------------------------------ time

    def place(self, t: float, epoch_ns: int) -> None:
        """Link time ``t`` is ``epoch_ns`` (ns since the epoch): the placing of every later time
        (another recorder's, to stamp alike; before the first message)."""
        self._t0, self._epoch_ns = t, epoch_ns

    @property
    def placing(self) -> tuple[float, int] | None:
        """(link time, ns since the epoch) of one instant, by which every time is placed (None before
        the first message)."""
        return None if self._t0 is None else (self._t0, self._epoch_ns)

    def ns(self, t: float) -> int:
        """Link-clock seconds -> ns since the epoch (the first time seen is when recording started)."""
        if self._t0 is None:
            self._t0 = t
        ns = self._epoch_ns + round((t - self._t0) * 1e9)
        return max(ns, 0)

    # ------------------------------------------------------------------ writing

    @contextlib.contextmanager
    def _writing(self) -> Iterator[None]:
        """Around every write to the file, one thread at a time and never cut in two by a signal's
        exception (:func:`omnibot.signals.held`: a record half written leaves its chunk unreadable):
        an ``OSError`` stops the file (:meth:`_failed`), nothing is raised."""
        with self._lock, held():
            try:
                yield
            except OSError as exc:
                self._failed(exc)

    def _failed(self, exc: OSError) -> None:
        """A write failed: no more writes to the file, one warning (stderr, :attr:`on_failure`)."""
        with self._fail_lock:
            if self.failure is not None:
                return
            why = exc.strerror or str(exc) or type(exc).__name__
            self.failure = (
                f"--log {self.path}: recording stopped, {why}; the robot goes on, the log keeps what "
                f"was written before (`omnibot log recover {self.path}` rewrites it whole)"
            )
            self._writer = None  # what it still holds (the open chunk) has no room: dropped
        log.debug("the log's write failed", exc_info=exc)
        with contextlib.suppress(OSError, ValueError):  # stderr on the same full disk, or closed
            print(f"omnibot: warning: {self.failure}", file=sys.stderr, flush=True)
        for callback in list(self.on_failure):
            try:
                callback(self.failure)
            except Exception:
                log.exception("a log failure callback failed")

    def _channel(self, writer: Writer, topic: str, typename: str) -> int:
        known = self._channels.get(topic)
        if known is not None:
            return known[0]
        schema = self._schemas.get(typename)
        if schema is None:
            schema = writer.register_schema(
                typename, "ros2msg", schemas.schema_text(typename).encode("utf-8")
            )
            self._schemas[typename] = schema
        channel = writer.register_channel(topic, "cdr", schema, {"offered_qos_profiles": offered_qos(topic)})
        self._channels[topic] = (channel, typename)
        return channel

    def write(self, topic: str, typename: str, message: Any, ns: int) -> None:
        """Serialize ``message`` (a ``typename`` object) onto ``topic`` at ``ns``."""
        if self.closed:
            return
        try:
            data = schemas.serialize(message, typename)
        except Exception:
            self.lost += 1
            log.exception("cannot serialize a %s for %s", typename, topic)
            return
        with self._lock:
            self.counts[topic] += 1
            sequence = self.counts[topic]
        for mirror in list(self.mirrors):
            try:
                mirror(topic, typename, data, ns)
            except Exception:
                # once, not once per message: the mirror is dropped, the file and the run go on
                log.exception("mirror %r failed on %s; it is dropped", mirror, topic)
                self.mirrors = [m for m in self.mirrors if m is not mirror]
        with self._writing():
            writer = self._writer
            if writer is None or self.closed:
                self._last_ns = max(self._last_ns, ns)
                return
            channel = self._channel(writer, topic, typename)
            writer.add_message(channel, log_time=ns, publish_time=ns, data=data, sequence=sequence)
            self._first_ns = ns if self._first_ns is None else min(self._first_ns, ns)
            self._last_ns = max(self._last_ns, ns)
            now = time.monotonic()
            if now - self._last_flush >= self.flush_period:
                self.flush()

    def flush(self) -> None:
        """Write the open chunk now."""
        with self._writing():
            writer = self._writer
            if not self.closed and writer is not None:
                writer.flush()  # type: ignore[no-untyped-call]
                self._last_flush = time.monotonic()

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
                    self._range(ns, sonar, event.distance),
                    ns,
                )

    def telemetry(self, tel: Telemetry) -> None:
        """Record a TEL sample: joint states, IMU, sonar ranges, the estimator's odometry and pose, and
        the simulator's truth when there is one."""
        ns = self.ns(tel.time)
        if tel.encoders is not None and self._joints and len(tel.encoders) == len(self._joints):
            self._joint_states(ns, tel)
        if tel.gyro_rate is not None or tel.heading is not None:
            self._imu(ns, tel)
        if tel.ranges is not None and self.robot is not None:
            for sonar, distance in zip(self.robot.sonars, tel.ranges, strict=False):
                self.write(
                    range_topic(sonar.name), "sensor_msgs/msg/Range", self._range(ns, sonar, distance), ns
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
        emulator's ``--truth`` file placed by :class:`omnibot.demos.seed000.ControllerClock`) on
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

    def add_metadata(self, name: str, values: dict[str, str]) -> None:
        """An MCAP metadata record ``name`` (nothing without a file, or once closed)."""
        with self._writing():
            writer = self._writer
            if writer is not None and not self.closed:
                writer.add_metadata(name, values)

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
            transform = schemas.new(
                "geometry_msgs/msg/TransformStamped",
                header=header(ns, "odom"),
                child_frame_id="base_link",
                transform=schemas.new(
                    "geometry_msgs/msg/Transform",
                    translation=vector(pose.x, pose.y),
                    rotation=quaternion(pose.theta),
                ),
            )
            self.write(
                TF,
                "tf2_msgs/msg/TFMessage",
                schemas.new("tf2_msgs/msg/TFMessage", transforms=[transform]),
                ns,
            )

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

    def _imu(self, ns: int, tel: Telemetry) -> None:
        unknown = np.zeros(9, dtype=np.float64)
        unknown[0] = -1.0  # REP 145: no linear acceleration measured
        orientation_cov = np.zeros(9, dtype=np.float64)
        if tel.heading is None:
            orientation_cov[0] = -1.0
        msg = schemas.new(
            "sensor_msgs/msg/Imu",
            header=header(ns, "imu_link"),
            orientation=quaternion(tel.heading or 0.0),
            orientation_covariance=orientation_cov,
            angular_velocity=vector(z=tel.gyro_rate or 0.0),
            angular_velocity_covariance=np.zeros(9, dtype=np.float64),
            linear_acceleration=vector(),
            linear_acceleration_covariance=unknown,
        )
        self.write(IMU, "sensor_msgs/msg/Imu", msg, ns)

    def _range(self, ns: int, sonar: Any, distance: float | None) -> Any:
        return schemas.new(
            "sensor_msgs/msg/Range",
            header=header(ns, f"sonar_{sonar.name}"),
            radiation_type=0,  # ULTRASOUND
            field_of_view=math.radians(sonar.cone_deg),
            min_range=float(sonar.min_range),
            max_range=float(sonar.max_range),
            range=math.inf if distance is None else float(distance),  # REP 117: no echo is +inf
            variance=float(sonar.noise_std) ** 2,
        )

    # ------------------------------------------------------------------ the end

    def close(self) -> None:
        """Detach, write the open chunk, rosbag2's metadata and the summary; close the file."""
        if self.closed:
            return
        for client in list(self._clients):
            self.detach(client)
        with self._lock:  # a write from another thread waits, then finds the file closed
            if self.closed:  # closed by another thread meanwhile
                return
            try:
                writer = self._writer
                if writer is not None:
                    with self._writing():
                        writer.add_metadata("rosbag2", {"serialized_metadata": self._rosbag2_metadata()})
                        writer.finish()  # type: ignore[no-untyped-call]
            finally:
                self.closed = True
                if self._file is not None:
                    with self._writing():
                        self._file.close()
            for mirror in self.mirrors:
                with contextlib.suppress(Exception):
                    mirror.close()

    def _rosbag2_metadata(self) -> str:
        assert self.path is not None
        channels = {topic: typename for topic, (_, typename) in self._channels.items()}
        start = self._first_ns or self._epoch_ns
        return rosbag2_metadata(self.path.name, channels, self.counts, start, self._last_ns)

    def __enter__(self) -> Recorder:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
