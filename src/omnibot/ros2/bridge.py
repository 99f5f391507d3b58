"""The ROS 2 bridge's publishing: a sink (odom, tf, imu, ranges, joint states, the URDF,
diagnostics) of the host runtime, with no loop of its own (its ``cmd_vel`` source:
:mod:`omnibot.ros2.cmd_vel`).

* :class:`Ros2Sink` feeds every cycle's telemetry and events to the MCAP recorder's message
  building (:class:`~omnibot.logs.recorder.Recorder` without a file) and publishes what it builds:
  ``odom`` (nav_msgs/Odometry with covariances) and ``/tf`` odom -> base_link from the runtime's
  estimator (the one a path follower steers by and ``initialpose`` sets), ``imu``,
  ``range/<sonar>``, ``scan`` (sensor_msgs/LaserScan of each revolution of the runtime's scanner,
  ``Cycle.scans``: sensor-data QoS, in the URDF's scanner frame), ``joint_states`` (the URDF's wheel
  joints), ``robot_description`` (transient-local), plus ``/tf_static`` (the sensors' frames, the
  scanner's among them, as in the URDF), ``battery_state``
  (sensor_msgs/BatteryState, once a second while the controller reports its voltage) and
  ``diagnostics`` (who drives and why, the latched emergency stop, refusals, the battery
  (:mod:`omnibot.ros2.battery`) and what the ``reporters`` add (:mod:`omnibot.ros2.diagnostics`): the path follower, odometry resets) once a second and at every notice.
  Every frame carries the robot's tf frame prefix (:mod:`omnibot.ros2.frames`). Stamps are the
  link's time placed on the wall clock by the process's :class:`~omnibot.ros2.clock.Timeline`; on
  a simulator ``/clock`` carries the simulated time each cycle, before what the cycle stamps
  (:mod:`omnibot.ros2.clock`).

It publishes through either backend (:mod:`omnibot.ros2.backend`) as CDR bytes: the recorder's as they
are when there is nothing to change in them (no frame prefix), else its message with the prefix,
serialized again (rosbags' serializer: a tenth of the cost of a cyclonedds sample built and serialized
in Python).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

from omnibot.client import WarnEvent
from omnibot.logs import (
    IMU,
    JOINT_STATES,
    ODOM,
    RANGE_PREFIX,
    ROBOT_DESCRIPTION,
    SCAN,
    TF,
    Recorder,
    header,
    quaternion,
    schemas,
    stamp,
    vector,
)
from omnibot.motion import Twist
from omnibot.protocol import codes
from omnibot.robot import RobotDescription
from omnibot.ros2.backend import DEFAULT, LATCHED, SENSOR_DATA, Profile, RosNode
from omnibot.ros2.battery import BATTERY_MESSAGES, battery_health, battery_state
from omnibot.ros2.clock import CLOCK, CLOCK_TYPE, Timeline
from omnibot.ros2.diagnostics import Diagnosed, Reporter
from omnibot.ros2.frames import prefixed, urdf_for_tf
from omnibot.runtime import Cycle

TF_STATIC = "/tf_static"
DIAGNOSTICS = "/diagnostics"
BATTERY = "battery_state"


GLOBAL = frozenset({TF, TF_STATIC, DIAGNOSTICS, CLOCK})
"""The topics all robots share (not in a robot's namespace)."""


def ros_topic(topic: str) -> str:
    """The ROS name the bridge publishes a log topic (``/odom``) on: relative (``odom``, in the robot's
    namespace) but for the shared ones (:data:`GLOBAL`)."""
    return topic if topic in GLOBAL else topic.lstrip("/")


class _Mirror:
    """The recorder's mirror: every message it builds goes to :meth:`Ros2Sink.publish`."""

    def __init__(self, sink: Ros2Sink) -> None:
        self.sink = sink

    def __call__(self, topic: str, typename: str, data: bytes, ns: int) -> None:
        self.sink.publish(topic, typename, data, ns)

    def close(self) -> None:
        """Nothing to release (the node is the sink's owner's)."""


def _triple(twist: Twist | None) -> str:
    """A twist as ``vx,vy,w`` (m/s, m/s, rad/s) for a diagnostic value ("" for none)."""
    return "" if twist is None else f"{twist.vx:.3f},{twist.vy:.3f},{twist.w:.3f}"


class Ros2Sink:
    """Publishes each cycle's state on ROS 2 topics (see the module docstring); ``prefix`` is the tf
    frame prefix (:func:`omnibot.ros2.frames.frame_prefix`); ``timeline`` places the stamps (the
    process's, shared by its robots); ``sim_time``: the link is a simulator's, publish ``/clock``."""

    def __init__(
        self,
        node: RosNode,
        robot: RobotDescription,
        *,
        prefix: str = "",
        reporters: Sequence[Reporter] = (),
        timeline: Timeline | None = None,
        sim_time: bool = False,
        diagnosed: Diagnosed | None = None,
    ) -> None:
        self.node = node
        self.diagnosed = diagnosed or Diagnosed.of(robot.name)
        self.robot = robot
        self.prefix = prefix
        self.reporters = list(reporters)
        self.timeline = timeline or Timeline()
        self.sim_time = sim_time
        self._writers: dict[str, Any] = {}
        for topic, typename, profile in self.topics(robot, sim_time=sim_time):
            self._writers[topic] = (node.writer(ros_topic(topic), typename, profile), typename)
        self.published: dict[str, int] = {}
        """Messages published per topic."""
        self._last_diagnostics = -math.inf
        self._last_battery = -math.inf
        self.voltage: float | None = None
        self.battery_stopped = False
        """The controller holds its battery stop (TEL state 4, WARN 43)."""
        """The battery voltage the controller last reported, V (None: it reports none)."""
        # the recorder builds the messages; the estimate is the runtime's (published each cycle)
        self.recorder = Recorder(None, mirrors=[_Mirror(self)])
        self._started = False

    @staticmethod
    def topics(robot: RobotDescription, *, sim_time: bool = False) -> list[tuple[str, str, Profile]]:
        """Every topic published: (name, type, QoS profile); ``/clock`` with ``sim_time``."""
        topics = [(CLOCK, CLOCK_TYPE, Profile(depth=1))] if sim_time else []
        topics += [
            (ODOM, "nav_msgs/msg/Odometry", DEFAULT),
            (TF, "tf2_msgs/msg/TFMessage", Profile(depth=100)),
            (TF_STATIC, "tf2_msgs/msg/TFMessage", LATCHED),
            (JOINT_STATES, "sensor_msgs/msg/JointState", DEFAULT),
            (ROBOT_DESCRIPTION, "std_msgs/msg/String", LATCHED),
            (DIAGNOSTICS, "diagnostic_msgs/msg/DiagnosticArray", DEFAULT),
            (BATTERY, "sensor_msgs/msg/BatteryState", DEFAULT),
        ]
        if robot.gyro is not None:
            topics.append((IMU, "sensor_msgs/msg/Imu", SENSOR_DATA))
        topics += [(RANGE_PREFIX + s.name, "sensor_msgs/msg/Range", SENSOR_DATA) for s in robot.sonars]
        if robot.scanner is not None:
            topics.append((SCAN, "sensor_msgs/msg/LaserScan", SENSOR_DATA))
        return topics

    def add_topic(self, topic: str, typename: str, profile: Profile) -> None:
        """Publish ``topic`` too (a log topic name, as :meth:`topics`'): another sink's, through
        :meth:`write` (``omnibot map``'s ``map``)."""
        if topic not in self._writers:
            self._writers[topic] = (self.node.writer(ros_topic(topic), typename, profile), typename)

    def publish(self, topic: str, typename: str, data: bytes, ns: int) -> None:
        """A recorder mirror: publish the message if it is one of ours (odom gets covariances, the URDF
        the frame prefix and ``base_link`` as its root)."""
        known = self._writers.get(topic)
        if known is None or known[1] != typename:
            return
        if not self.prefix and topic != ROBOT_DESCRIPTION:
            known[0].write_cdr(data)  # the recorder's bytes are the message: nothing to redo
            self.published[topic] = self.published.get(topic, 0) + 1
            return
        message = schemas.deserialize(data, typename)
        if topic == ROBOT_DESCRIPTION:
            message.data = urdf_for_tf(message.data, self.prefix)
        self.write(topic, message)

    def write(self, topic: str, message: Any) -> None:
        """Publish a rosbags message object on ``topic`` (its frames prefixed)."""
        writer, typename = self._writers[topic]
        message = prefixed(message, self.prefix)
        writer.write_cdr(schemas.serialize(message, typename))
        self.published[topic] = self.published.get(topic, 0) + 1

    def start(self, t: float) -> None:
        """The URDF on ``robot_description`` and the sensors' frames on ``/tf_static``."""
        self._started = True
        self.recorder.place(*self.timeline.origin(t))
        self.recorder.start(self.robot, t=t)
        self.recorder.estimator = None  # the runtime's estimate is published instead
        self.write(TF_STATIC, self.static_transforms(self.recorder.ns(t)))

    def static_transforms(self, ns: int) -> Any:
        """base_link -> each sonar, the imu and the scanner, placed as the URDF places them."""
        robot = self.robot
        z = robot.footprint.height / 2
        frames = [(f"sonar_{s.name}", s.x, s.y, z, s.angle) for s in robot.sonars]
        if robot.gyro is not None:
            frames.append(("imu_link", 0.0, 0.0, z, 0.0))
        scanner = robot.scanner
        if scanner is not None:  # the scan plane's height above the floor; base_link is at the axles
            axle_height = max(w.radius for w in robot.wheels)
            frames.append((scanner.frame, scanner.x, scanner.y, scanner.z - axle_height, scanner.yaw))
        transforms = [
            schemas.new(
                "geometry_msgs/msg/TransformStamped",
                header=header(ns, "base_link"),
                child_frame_id=name,
                transform=schemas.new(
                    "geometry_msgs/msg/Transform", translation=vector(x, y, h), rotation=quaternion(yaw)
                ),
            )
            for name, x, y, h, yaw in frames
        ]
        return schemas.new("tf2_msgs/msg/TFMessage", transforms=transforms)

    def __call__(self, cycle: Cycle) -> None:
        """The runtime's cycle: its telemetry and events published, the estimate after new samples,
        its scans, the battery and diagnostics once a second (diagnostics also when a notice came)."""
        if not self._started:
            self.start(cycle.t)
        if self.sim_time:
            self.clock(cycle.t)
        sampled = False
        for event in (*cycle.telemetry, *cycle.events):
            self.recorder.event(event)
        for tel in cycle.telemetry:
            sampled |= tel.encoders is not None
            if tel.battery is not None:
                self.voltage = tel.battery
            if tel.state is not None:
                self.battery_stopped = tel.state == codes.STATE_BATTERY
        for event in cycle.events:
            if isinstance(event, WarnEvent) and event.code == codes.W_BATTERY_STOP:
                self.battery_stopped = True
        if sampled and cycle.estimate is not None:
            self.recorder.estimate(cycle.t, cycle.estimate)
        if SCAN in self._writers:
            for scan in cycle.scans:
                self.recorder.scan(scan)
        if self.voltage is not None and cycle.now - self._last_battery >= 1.0:
            self._last_battery = cycle.now
            self.write(
                BATTERY,
                battery_state(self.robot, self.voltage, self.recorder.ns(cycle.t), self.battery_stopped),
            )
        if cycle.now - self._last_diagnostics >= 1.0 or cycle.notices:
            self._last_diagnostics = cycle.now
            self.write(DIAGNOSTICS, self.diagnostics(cycle))

    def clock(self, t: float) -> None:
        """``/clock`` at link time ``t`` (the simulated time), unless the process's ``/clock`` is
        already there (another robot's cycle)."""
        ns = self.recorder.ns(t)
        if self.timeline.advance(ns):
            self.write(CLOCK, schemas.new(CLOCK_TYPE, clock=stamp(ns)))

    def diagnostics(self, cycle: Cycle) -> Any:
        """diagnostic_msgs/DiagnosticArray: control (who drives, why, locks), the battery, and what the
        reporters add."""
        decision = cycle.decision
        worst = max((n.level for n in cycle.notices), key=("info", "warn", "error").index, default="info")
        level = 2 if cycle.latched or decision.estop or worst == "error" else 1 if worst == "warn" else 0
        text = "; ".join(n.text for n in cycle.notices) or decision.reason
        if cycle.latched:
            what = "battery stop (battery flat)" if cycle.latch_reason == "battery" else "emergency stop"
            text = f"{what} latched on the controller; " + text
        sent, asked, achieved = cycle.sent, cycle.decision.twist, cycle.achieved
        statuses = [
            self.diagnosed.status(
                level,
                "control",
                text,
                {
                    "source": decision.source or "none",
                    "lock": decision.lock or "none",
                    "emergency_stop": cycle.latched or decision.estop,
                    "sent": _triple(sent),
                    "asked": _triple(asked),
                    "achieved": _triple(achieved),
                },
            ),
            self._battery_status(),
        ]
        statuses += [report() for report in self.reporters]
        return schemas.new(
            "diagnostic_msgs/msg/DiagnosticArray",
            header=header(self.recorder.ns(cycle.t), ""),
            status=statuses,
        )

    def _battery_status(self) -> Any:
        nominal = self.robot.battery.voltage
        if self.voltage is None:
            return self.diagnosed.status(
                0,
                "battery",
                "not reported by the controller (no battery_state published)",
                {"nominal_voltage": nominal},
            )
        level = battery_health(self.robot, self.voltage, self.battery_stopped)
        b = self.robot.battery
        return self.diagnosed.status(
            {"low": 1, "limited": 1, "flat": 2}.get(level, 0),
            "battery",
            f"{self.voltage:.2f} V: {BATTERY_MESSAGES.get(level, level)}",
            {
                "voltage": f"{self.voltage:.3f}",
                "nominal_voltage": nominal,
                "level": level,
                "warn_voltage": round(b.warn_v, 3),
                "limit_voltage": round(b.limit_v, 3),
                "stop_voltage": round(b.stop_v, 3),
            },
        )

    def close(self) -> None:
        """Stop publishing (the node is closed by its owner)."""
        self.recorder.close()
