"""``cmd_vel`` into the runtime's arbitration, as geometry_msgs/Twist or TwistStamped.

:class:`CmdVelSource` takes each command as it arrives: a listener on its readers (in the DDS
receive thread) wakes the runtime (:mod:`omnibot.runtime.wakeup`) and does nothing else (the client
is the runtime loop's); the runtime's reaction asks the source, arbitrates and sends the VEL then,
not at the next cycle. Every cycle asks it as well (and takes what arrived where no listener could
be set). It proposes the newest twist while it is younger than ``cmd_vel_timeout`` (ros2_controllers' name and 0.5 s default), ramped at the
robot's acceleration limits (as ros2_controllers' drive controllers apply theirs; the ramp's
acceleration goes with the VEL); then it is silent, and the VEL watchdog (:data:`WATCHDOG`) stops the
robot (on the wheel-speed loop: braking at the same limits).

Both types on one topic name, by what the publishers in the graph offer: the participant's
DCPSPublication builtin topic names every writer discovered, with its topic and type. The source
reads TwistStamped from the start (Nav2's from Kilted on) and adds a Twist reader when a Twist
publisher appears on ``cmd_vel`` (teleop_twist_joy's and Jazzy's Nav2's default); a publisher of any
other type is told of once, in one line (its commands are not taken: the robot does not drive
silently at 0). ``forced`` (``--twist``) takes that one type only and says so of a publisher of the
other.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable
from typing import Any

from omnibot.motion import Twist
from omnibot.ros2.backend import RosNode
from omnibot.ros2.dds import topic_name
from omnibot.ros2.types import from_dds, ros_name
from omnibot.runtime import Cycle, Proposal, Wake
from omnibot.teleop import RampedTwist, TwistLimits

log = logging.getLogger("omnibot.ros2")

CMD_VEL = "cmd_vel"
CMD_VEL_PRIORITY = 90
"""Below the page's stick (100) and a pad (200): a person overrides Nav2; above scripts (50)."""
CMD_VEL_TIMEOUT = 0.5
"""s a cmd_vel stays in force (ros2_controllers' ``cmd_vel_timeout``)."""
WATCHDOG = 0.2
"""s: the VEL timeout of cmd_vel's commands (the robot stops this long after they end)."""
TWIST = "geometry_msgs/msg/Twist"
TWIST_STAMPED = "geometry_msgs/msg/TwistStamped"
TYPES = (TWIST_STAMPED, TWIST)

Notify = Callable[[str, str], None]
"""``notify(level, text)``: a runtime notice (status lines, diagnostics)."""


def _warn(level: str, text: str) -> None:
    log.warning("%s", text)


def listen(reader: Any, wake: Wake) -> Any:
    """Have ``reader`` call ``wake()`` (in its middleware's thread) whenever data arrives: through
    its own ``on_data(callback)`` where it has one (another backend's reader), else a cyclonedds
    listener. Returns what keeps the listener alive (None: ``reader`` cannot tell, and is polled)."""
    on_data = getattr(reader, "on_data", None)
    if callable(on_data):
        on_data(wake)
        return on_data
    if not callable(getattr(reader, "set_listener", None)):
        return None
    from cyclonedds.core import Listener

    def available(_reader: Any) -> None:
        wake()

    listener = Listener(on_data_available=available)  # type: ignore[no-untyped-call]
    reader.set_listener(listener)
    return listener


class CmdVelSource:
    """``cmd_vel`` into the runtime's arbitration (see the module docstring)."""

    def __init__(
        self,
        node: RosNode,
        *,
        forced: str | None = None,
        timeout: float = CMD_VEL_TIMEOUT,
        priority: int = CMD_VEL_PRIORITY,
        name: str = "ros2",
        limits: TwistLimits | None = None,
        period: float = 0.02,
        notify: Notify = _warn,
    ) -> None:
        if forced is not None and forced not in TYPES:
            raise ValueError(f"cmd_vel is {' or '.join(TYPES)}, not {forced}")
        self.name = name
        self.priority = priority
        self.timeout = timeout
        self.watchdog = WATCHDOG
        self.wait_reply = False
        self.node = node
        self.forced = forced
        self.notify = notify
        self.readers: dict[str, Any] = {}
        """The readers made so far, by ROS type."""
        self.wake: Wake | None = None
        self.listeners: dict[str, Any] = {}
        """Each reader's listener, by ROS type (while the runtime wakes on the source's commands)."""
        self.reader = self._read(forced or TWIST_STAMPED)
        self.publications = node.publications()
        self._dds_topic = topic_name(CMD_VEL, node.namespace)
        self.refused: set[str] = set()
        """Types of publishers told of (not taken)."""
        self.twist: Twist | None = None
        self.received_at = -math.inf
        self.received = 0
        """Messages taken so far."""
        self.message: Any = None
        """The newest message taken (a rosbags Twist or TwistStamped: its header says which it was)."""
        self.ramped = RampedTwist(limits, period)
        """The robot's acceleration limits on the twists (as ros2_control's controllers apply theirs)."""

    def _read(self, typename: str) -> Any:
        reader = self.readers.get(typename)
        if reader is None:
            reader = self.readers[typename] = self.node.reader(CMD_VEL, typename)
            if self.wake is not None:
                self.listeners[typename] = listen(reader, self.wake)
        return reader

    def wake_with(self, wake: Wake) -> None:
        """Wake the runtime (``wake``, from the readers' thread) when a command arrives (the runtime
        hands it over when the source is added); the listeners go when the node closes, before its
        participant (:meth:`unlisten`)."""
        if self.wake is None:
            closers = getattr(self.node, "closers", None)
            if closers is not None:
                closers.append(self.unlisten)
        self.wake = wake
        for typename, reader in self.readers.items():
            self.listeners[typename] = listen(reader, wake)

    def unlisten(self) -> None:
        """Take the listeners off the readers: no call into Python from DDS's threads once the
        runtime is gone (nor into a listener the garbage collector may free first)."""
        self.wake = None
        for typename, listener in self.listeners.items():
            reader = self.readers[typename]
            if listener is None:
                continue
            on_data = getattr(reader, "on_data", None)
            if callable(on_data):
                on_data(None)
            elif callable(getattr(reader, "set_listener", None)):
                reader.set_listener(None)
        self.listeners.clear()

    @property
    def event_driven(self) -> bool:
        """Every reader wakes the runtime when a command arrives (else the cycles take them)."""
        return bool(self.listeners) and all(self.listeners.get(t) is not None for t in self.readers)

    @property
    def body_accel(self) -> tuple[float, float, float] | None:
        """The ramp's planned acceleration of the last proposal, sent with its VEL."""
        return self.ramped.body_accel

    def discover(self) -> None:
        """Readers for the publishers on ``cmd_vel`` discovered since the last call; a publisher of
        a type not taken is told of once per type."""
        for pub in self.publications.take(N=64):
            if getattr(pub, "topic_name", None) != self._dds_topic or not getattr(pub, "type_name", None):
                continue
            typename = ros_name(pub.type_name)
            if typename in self.readers or typename in self.refused:
                continue
            if typename in TYPES and self.forced is None:
                self._read(typename)
                log.info("cmd_vel: a %s publisher: taking it", typename)
                continue
            self.refused.add(typename)
            if typename in TYPES:
                why = f"--twist takes only {TWIST} (without --twist both are taken)"
            else:
                why = f"omnibot drives on {TWIST} or {TWIST_STAMPED}"
            self.notify("warn", f"cmd_vel: a publisher of {typename} ignored: {why}")

    def _newest(self) -> tuple[str, Any] | None:
        """(type, sample): the newest sample taken from the readers (by its source timestamp)."""
        newest: tuple[int, str, Any] | None = None
        for typename, reader in self.readers.items():
            samples = [s for s in reader.take(N=64) if hasattr(s, "__idl_typename__")]
            self.received += len(samples)
            if samples:
                at = getattr(getattr(samples[-1], "sample_info", None), "source_timestamp", 0)
                if newest is None or at >= newest[0]:
                    newest = (at, typename, samples[-1])
        return None if newest is None else (newest[1], newest[2])

    def propose(self, cycle: Cycle) -> Proposal | None:
        """The newest cmd_vel while younger than the timeout (on ``cycle.now``), else None (asked by
        every cycle, and by the runtime's reaction to a wake)."""
        self.discover()
        newest = self._newest()
        if newest is not None:
            typename, sample = newest
            msg = from_dds(sample, typename)
            body = msg.twist if typename == TWIST_STAMPED else msg
            values = (body.linear.x, body.linear.y, body.angular.z)
            if all(math.isfinite(v) for v in values):
                self.twist = Twist(*values)
                self.message = msg
                self.received_at = cycle.now
            else:
                log.warning("cmd_vel with a non-finite value ignored: %s", values)
        fresh = self.twist is not None and cycle.now - self.received_at <= self.timeout
        twist = self.ramped(cycle, self.twist if fresh else None)
        return None if twist is None else Proposal(twist)
