"""The one interface the bridge speaks ROS 2 through, and the choice of the backend behind it.

Two backends, chosen once at start by ``--ros-backend`` (:func:`choose`):

* ``rclpy`` (:mod:`omnibot.ros2.rclpy_backend`): a genuine rclpy node on the user's rmw, where
  ``import rclpy`` works (a ROS 2 install, or the PyPI ROS wheels): node name and namespace, the
  bridge's options as ROS parameters, services over any rmw, ``use_sim_time``;
* ``dds`` (:mod:`omnibot.ros2.dds`): one cyclonedds participant on rmw_cyclonedds' wire, where only pip
  is at hand; it announces its node in the ROS graph as rmw does (``ros_discovery_info``), but serves
  no parameters, and its services answer rmw_cyclonedds clients only.

``auto`` is ``rclpy`` when it can be imported, else ``dds``.

Both hand over and take the same samples: cyclonedds' :class:`~cyclonedds.idl.IdlStruct` of a ROS
type (:mod:`omnibot.ros2.types`); the rclpy backend carries them as serialized CDR, which is what rmw
puts on the wire. Both backends' writers also take CDR bytes as they are (:meth:`Writer.write_cdr`):
the recorder's messages go out without being built again as samples.
"""

from __future__ import annotations

import importlib.util
import logging
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any, Protocol

from omnibot.errors import ConfigError

BACKENDS = ("auto", "rclpy", "dds")
NODE_NAME = "omnibot"
"""The bridge's ROS node name (in the robot's namespace: ``/r1/omnibot``)."""


@dataclass(frozen=True)
class Profile:
    """A QoS profile of rclpy's."""

    reliable: bool = True
    depth: int = 10
    transient_local: bool = False


DEFAULT = Profile()
SENSOR_DATA = Profile(reliable=False, depth=5)
LATCHED = Profile(depth=1, transient_local=True)

Check = Callable[[Any], str | None]
"""A parameter's new value: None when it may be set, else why not."""


def _keep(value: Any) -> None:
    """A read-only parameter's assign: nothing to do."""


@dataclass(frozen=True)
class Parameter:
    """One of the bridge's options as a ROS parameter: read-only unless ``check`` admits new values,
    which ``assign`` then puts in force (once every parameter of the request was admitted)."""

    name: str
    value: bool | int | float | str
    description: str
    check: Check | None = None
    assign: Callable[[Any], None] = _keep

    @property
    def read_only(self) -> bool:
        """Set once, at start (the option it comes from)."""
        return self.check is None


class Reader(Protocol):
    """A subscription: :meth:`take` hands over the samples that arrived, oldest first."""

    def take(self, N: int = 1) -> list[Any]:
        """At most ``N`` samples, without blocking."""
        ...


class Writer(Protocol):
    """A publisher of DDS samples."""

    def write(self, sample: Any) -> None:
        """Publish ``sample`` (an IdlStruct of the writer's type)."""
        ...

    def write_cdr(self, data: bytes) -> None:
        """Publish ``data``, a message of the writer's type as CDR with its encapsulation header (as
        :func:`omnibot.logs.schemas.serialize` makes it), as it is."""
        ...


class Service(Protocol):
    """A service whose requests the runtime answers: :meth:`poll` once a cycle."""

    answered: int

    def poll(self) -> int:
        """Answer the requests that arrived (without blocking); how many were answered."""
        ...


Handler = Callable[[], tuple[bool, str]]
"""A std_srvs/srv/Trigger handler: (success, message)."""


class RosNode(Protocol):
    """What the bridge, the cmd_vel and path sources, the odometry services and the map publisher use
    of a ROS 2 node."""

    backend: str
    """``rclpy`` or ``dds``."""
    name: str
    namespace: str
    """Without slashes (``r1``, or ``""``)."""
    domain_id: int
    scope: str
    """Discovery range: ``LOCALHOST``, ``OFF`` or ``SUBNET``."""
    closers: list[Callable[[], object]]
    """Called by :meth:`close` first, newest first."""

    def writer(self, name: str, typename: str, profile: Profile = DEFAULT) -> Writer:
        """A publisher of ``typename`` on the ROS topic ``name``."""
        ...

    def reader(self, name: str, typename: str, profile: Profile = DEFAULT) -> Reader:
        """A subscription of ``typename`` on the ROS topic ``name``."""
        ...

    def publications(self) -> Reader:
        """Every publisher discovered (``topic_name`` and ``type_name`` as on DDS), each once."""
        ...

    def trigger_service(self, name: str, handler: Handler) -> Service:
        """The std_srvs/srv/Trigger service ``name``, answered with ``handler()``."""
        ...

    def declare(self, parameters: Sequence[Parameter]) -> None:
        """Offer ``parameters`` (as ROS parameters where the backend can)."""
        ...

    def close(self) -> None:
        """Release what the node opened."""
        ...


def run_closers(closers: list[Callable[[], object]]) -> None:
    """Call ``closers``, newest first, each whatever the others did (a failure is logged: on the way
    out, the node is released anyway)."""
    while closers:
        closer = closers.pop()
        try:
            closer()
        except Exception:
            logging.getLogger("omnibot.ros2").exception("closing %r failed", closer)


def rclpy_importable() -> bool:
    """``import rclpy`` would work here."""
    return importlib.util.find_spec("rclpy") is not None


def choose(name: str) -> str:
    """``rclpy`` or ``dds``: the backend ``--ros-backend name`` means here (one line when rclpy is asked
    for and cannot be imported)."""
    if name not in BACKENDS:
        raise ConfigError(f"--ros-backend is one of {', '.join(BACKENDS)}, not {name!r}", key="--ros-backend")
    if name == "auto":
        return "rclpy" if rclpy_importable() else "dds"
    if name == "rclpy" and not rclpy_importable():
        raise ConfigError(
            "--ros-backend rclpy: rclpy cannot be imported here (source a ROS 2 install, or use "
            "--ros-backend dds)",
            key="--ros-backend",
        )
    return name
