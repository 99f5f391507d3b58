"""One DDS participant with ROS 2's wire conventions (rmw_cyclonedds'), on cyclonedds.

* topics ``rt/<namespace>/<name>`` (an absolute name such as ``/tf`` is not namespaced);
* QoS as rclpy's defaults: reliable, keep-last 10, volatile; sensor data best-effort keep-last 5;
  ``robot_description`` transient-local keep-last 1 (robot_state_publisher's);
* each reader and writer carries ``typehash=RIHS01_<hex>;`` in its USER_DATA, as rmw puts it;
* Fast DDS's XTypes type information is ignored (:data:`COMPATIBILITY`): endpoints match on type
  names, as between rmw implementations;
* the node in the ROS graph as rmw announces it (rmw_dds_common's ``GraphCache``): the participant's
  USER_DATA says ``enclave=/;`` and ``ros_discovery_info`` (rmw_dds_common/msg/ParticipantEntitiesInfo,
  reliable, transient-local, keep-last 1, without the ``rt/`` prefix) names the participant's GID,
  the node's name and namespace and the GIDs of its readers and writers (a GID is the entity's
  16-byte DDS GUID, as rmw_cyclonedds' ``convert_guid_to_gid``), published again whenever the node
  makes an endpoint: ``ros2 node list`` and ``ros2 topic info -v`` name the node. Its USER_DATA
  carries no type hash (rosbags' description of ``Gid`` is not rosidl's, so its hash would be wrong);
  the graph matches on type names;
* a writer takes samples or CDR bytes as they are (:class:`Writer`: the recorder's messages, serialized
  by rosbags, go out without a sample being built);
* ``ROS_DOMAIN_ID``, ``ROS_AUTOMATIC_DISCOVERY_RANGE`` (``LOCALHOST``, ``OFF``, ``SUBNET``) and the
  older ``ROS_LOCALHOST_ONLY=1`` mean what they mean to rmw: localhost-only discovery is unicast to
  127.0.0.1 with multicast off.

Under pytest a participant is refused outside a private network namespace
(:func:`~omnibot.ros2.netns.check_participant_allowed`), and discovery is always localhost-only.
"""

from __future__ import annotations

import logging
import os
import re
import threading
from collections.abc import Callable, Mapping, Sequence
from typing import Any

from omnibot.errors import ConfigError
from omnibot.logs import type_hash
from omnibot.ros2 import netns
from omnibot.ros2.backend import (
    DEFAULT,
    LATCHED,
    NODE_NAME,
    SENSOR_DATA,
    Handler,
    Parameter,
    Profile,
    run_closers,
)
from omnibot.ros2.types import dds_type, request_type

try:
    from cyclonedds._clayer import ddspy_write
    from cyclonedds.builtin import BuiltinDataReader, BuiltinTopicDcpsPublication
    from cyclonedds.core import DDSException, Qos
    from cyclonedds.domain import Domain, DomainParticipant
    from cyclonedds.pub import DataWriter
    from cyclonedds.qos import Policy
    from cyclonedds.sub import DataReader
    from cyclonedds.topic import Topic
    from cyclonedds.util import duration
except ImportError as exc:  # pragma: no cover - the message says how to get it
    raise ImportError("the ROS 2 bridge needs cyclonedds: pip install 'omnibot[ros2]'") from exc

_RELIABLE = Policy.Reliability.Reliable(max_blocking_time=duration(milliseconds=100))


__all__ = ["DEFAULT", "LATCHED", "SENSOR_DATA", "Node", "Profile", "Writer", "qos", "topic_name"]


def qos(profile: Profile, typename: str, user_data: str = "") -> Qos:
    """The DDS QoS of ``profile`` with ``user_data`` and ``typename``'s RIHS01 hash in USER_DATA (none
    for an empty ``typename``)."""
    hashed = f"typehash={type_hash(typename)};" if typename else ""
    return Qos(
        _RELIABLE if profile.reliable else Policy.Reliability.BestEffort,
        Policy.History.KeepLast(profile.depth),
        Policy.Durability.TransientLocal if profile.transient_local else Policy.Durability.Volatile,
        Policy.Userdata(f"{user_data}{hashed}".encode()),
    )


def topic_name(name: str, namespace: str = "", kind: str = "rt", suffix: str = "") -> str:
    """The DDS topic of the ROS topic ``name`` in ``namespace``: ``kind`` (``rt`` a topic; ``rq`` and
    ``rr`` a service's requests and replies) + ``/`` + the fully qualified name + ``suffix``
    (``Request``, ``Reply``), as rmw_cyclonedds' ``make_fqtopic``."""
    if name.startswith("/"):
        return kind + name + suffix
    ns = namespace.strip("/")
    return f"{kind}/{ns}/{name}{suffix}" if ns else f"{kind}/{name}{suffix}"


def domain_id(env: Mapping[str, str]) -> int:
    """``ROS_DOMAIN_ID`` (0 when unset)."""
    text = env.get("ROS_DOMAIN_ID", "").strip()
    if not text:
        return 0
    if not text.isdigit() or int(text) > 232:
        raise ConfigError(f"ROS_DOMAIN_ID must be an integer 0-232, got {text!r}", key="ROS_DOMAIN_ID")
    return int(text)


def discovery_range(env: Mapping[str, str]) -> str:
    """``LOCALHOST``, ``OFF`` or ``SUBNET`` as rmw reads the environment (``SUBNET`` by default; the
    old ``ROS_LOCALHOST_ONLY=1`` means ``LOCALHOST``); always ``LOCALHOST`` under pytest but on a
    test network's host (:func:`~omnibot.ros2.netns.in_test_network`)."""
    if netns.under_pytest() and not netns.in_test_network():
        return "LOCALHOST"
    value = env.get("ROS_AUTOMATIC_DISCOVERY_RANGE", "").strip().upper()
    if value in ("", "SYSTEM_DEFAULT"):
        return "LOCALHOST" if env.get("ROS_LOCALHOST_ONLY", "").strip() == "1" else "SUBNET"
    if value not in ("LOCALHOST", "OFF", "SUBNET"):
        raise ConfigError(
            f"ROS_AUTOMATIC_DISCOVERY_RANGE must be LOCALHOST, OFF or SUBNET, got {value!r}",
            key="ROS_AUTOMATIC_DISCOVERY_RANGE",
        )
    return value


_PEER = re.compile(r"[A-Za-z0-9_.:\-\[\]]+")


def static_peers(env: Mapping[str, str]) -> tuple[str, ...]:
    """``ROS_STATIC_PEERS``: the addresses or host names between its ``;`` (none when unset)."""
    peers = tuple(p.strip() for p in env.get("ROS_STATIC_PEERS", "").split(";") if p.strip())
    for peer in peers:
        if not _PEER.fullmatch(peer):
            raise ConfigError(
                f"ROS_STATIC_PEERS holds addresses or host names separated by ';', not {peer!r}",
                key="ROS_STATIC_PEERS",
            )
    return peers


FAST_DDS = "1.15"
"""eProsima Fast DDS's RTPS vendor id (ROS 2's default rmw)."""
COMPATIBILITY = f"<Compatibility><IgnoreTypeInformation>{FAST_DDS}</IgnoreTypeInformation></Compatibility>"
"""Match Fast DDS's endpoints on type names, as rmw does (the RIHS01 hash rides in USER_DATA), not on
its XTypes type information: Kilted's Fast DDS (3.x) answers cyclonedds' request for the minimal type
of a message with arrays or sequences (Odometry, Imu, JointState) with the complete one, the type
never resolves and the endpoints never match (Range and Twist, without collections, did)."""


def config_xml(domain: int, scope: str, static: tuple[str, ...] = ()) -> str:
    """cyclonedds' configuration for ``scope`` and the ``static`` peers (``ROS_STATIC_PEERS``), as
    rmw_cyclonedds makes it for that discovery range: ``LOCALHOST`` unicast to 127.0.0.1 and the
    static peers, multicast off; ``SUBNET`` multicast and the static peers, participant indexes
    (whose ports a peer's unicast discovery tries) given out automatically; ``OFF`` no discovery,
    static peers ignored (rmw warns)."""
    general = ""
    peers = ""
    listed = "".join(f'<Peer address="{peer}"/>' for peer in static)
    if scope == "LOCALHOST":
        general = (
            '<General><Interfaces><NetworkInterface address="127.0.0.1"/></Interfaces>'
            "<AllowMulticast>false</AllowMulticast></General>"
        )
        peers = f'<Peers><Peer address="127.0.0.1"/>{listed}</Peers><ParticipantIndex>auto</ParticipantIndex>'
        peers += "<MaxAutoParticipantIndex>100</MaxAutoParticipantIndex>"
    elif scope == "OFF":
        general = "<General><AllowMulticast>false</AllowMulticast></General>"
        peers = "<ParticipantIndex>none</ParticipantIndex>"
        if static:
            logging.getLogger("omnibot.ros2").warning(
                "ROS_AUTOMATIC_DISCOVERY_RANGE is OFF: ROS_STATIC_PEERS (%s) ignored", ";".join(static)
            )
    elif static:
        peers = f"<Peers>{listed}</Peers><ParticipantIndex>auto</ParticipantIndex>"
        peers += "<MaxAutoParticipantIndex>32</MaxAutoParticipantIndex>"
    discovery = f"<Discovery>{peers}</Discovery>" if peers else ""
    return f'<CycloneDDS><Domain Id="{domain}">{general}{COMPATIBILITY}{discovery}</Domain></CycloneDDS>'


_DOMAINS: dict[int, tuple[Any, tuple[str, tuple[str, ...]]]] = {}
_DOMAINS_LOCK = threading.Lock()
_ENTITIES = threading.RLock()
"""Entities are made one at a time in a process: cyclonedds fails to make the topics of one type from
two threads at once (several robots open their nodes in threads of their own)."""


def _domain(domain: int, scope: str, static: tuple[str, ...] = ()) -> Any:
    """The process's one configured domain ``domain`` (cyclonedds allows one configuration each; the
    robots of one process open their nodes in threads of their own)."""
    with _DOMAINS_LOCK:
        known = _DOMAINS.get(domain)
        if known is not None:
            if known[1] != (scope, static):
                raise ConfigError(
                    f"DDS domain {domain} is already open with discovery range {known[1][0]}, "
                    f"static peers {';'.join(known[1][1]) or 'none'}"
                )
            return known[0]
        made = Domain(domain, config_xml(domain, scope, static))
        _DOMAINS[domain] = (made, (scope, static))
        return made


GRAPH_TOPIC = "ros_discovery_info"
GRAPH_TYPE = "rmw_dds_common/msg/ParticipantEntitiesInfo"
ENCLAVE = b"enclave=/;"
"""The participant's USER_DATA, as rmw's (the default security enclave)."""


def gid(entity: Any) -> bytes:
    """The 16-byte GUID of a cyclonedds entity, as rmw_cyclonedds makes an ``rmw_gid_t`` of it."""
    return bytes(entity.guid.bytes)


class Writer(DataWriter[Any]):
    """A DataWriter that also publishes CDR bytes as they are (rmw's ``publish_serialized``): what
    rosbags' serializer makes is what cyclonedds' own would, byte for byte (XCDR1 with its
    encapsulation header), at a tenth of the cost of building the sample and serializing it in Python."""

    def write_cdr(self, data: bytes) -> None:
        """Publish ``data``: a message of the writer's type as CDR with its encapsulation header, padded
        to 4 bytes as cyclonedds pads its own (its C layer copies the bytes into the sample it sends:
        the call :meth:`write` ends in)."""
        padded = bytes(data).ljust((len(data) + 3) & ~3, b"\0")
        status = ddspy_write(self._ref, padded)
        if status < 0:
            raise DDSException(status, f"Occurred while writing CDR bytes in {self!r}")


class Node:
    """A participant with ROS 2 naming and QoS: :meth:`writer` and :meth:`reader` of ROS types, the
    node ``name`` in ``namespace`` announced on :data:`GRAPH_TOPIC`."""

    backend = "dds"

    def __init__(
        self, namespace: str = "", env: Mapping[str, str] | None = None, name: str = NODE_NAME
    ) -> None:
        env = os.environ if env is None else env
        netns.check_participant_allowed()
        self.name = name
        self.namespace = namespace.strip("/")
        self.domain_id = domain_id(env)
        self.scope = discovery_range(env)
        self.static_peers = static_peers(env)
        self._domain = _domain(self.domain_id, self.scope, self.static_peers)
        with _ENTITIES:
            self.participant = DomainParticipant(self.domain_id, qos=Qos(Policy.Userdata(ENCLAVE)))
        self._topics: dict[tuple[str, str], Any] = {}
        """Topics made, by DDS name and ROS type (one name may carry two types: cmd_vel's)."""
        self._services = 0
        self.closers: list[Callable[[], object]] = []
        """Called by :meth:`close` first, newest first (what the bridge opened with the node: a scanner)."""
        self.parameters: dict[str, Parameter] = {}
        """The bridge's options (no parameter services on this backend)."""
        self.readers: list[bytes] = []
        self.writers: list[bytes] = []
        """The GIDs of the node's endpoints, as announced."""
        with _ENTITIES:
            topic = Topic(self.participant, GRAPH_TOPIC, dds_type(GRAPH_TYPE))
            self._graph: Any = DataWriter(self.participant, topic, qos=qos(LATCHED, ""))
        self._announce()

    def _announce(self) -> None:
        """Publish the node's entities on :data:`GRAPH_TOPIC` (rmw_dds_common's ParticipantEntitiesInfo)."""
        make: Any = dds_type("rmw_dds_common/msg/Gid")
        entities: Any = dds_type("rmw_dds_common/msg/NodeEntitiesInfo")
        participant: Any = dds_type(GRAPH_TYPE)
        info = entities(
            node_namespace="/" + self.namespace,
            node_name=self.name,
            reader_gid_seq=[make(data=list(g)) for g in self.readers],
            writer_gid_seq=[make(data=list(g)) for g in self.writers],
        )
        self._graph.write(
            participant(gid=make(data=list(gid(self.participant))), node_entities_info_seq=[info])
        )

    def _topic(self, name: str, typename: str) -> Any:
        dds = topic_name(name, self.namespace)
        topic = self._topics.get((dds, typename))
        if topic is None:
            topic = Topic(self.participant, dds, dds_type(typename))
            self._topics[dds, typename] = topic
        return topic

    def writer(self, name: str, typename: str, profile: Profile = DEFAULT) -> Writer:
        """A DataWriter of ``typename`` on the ROS topic ``name`` (samples or CDR bytes)."""
        with _ENTITIES:
            made = Writer(self.participant, self._topic(name, typename), qos=qos(profile, typename))
            self.writers.append(gid(made))
            self._announce()
        return made

    def reader(self, name: str, typename: str, profile: Profile = DEFAULT) -> Any:
        """A DataReader of ``typename`` on the ROS topic ``name``."""
        with _ENTITIES:
            made = DataReader(self.participant, self._topic(name, typename), qos=qos(profile, typename))
            self.readers.append(gid(made))
            self._announce()
        return made

    def publications(self) -> Any:
        """A reader of the DCPSPublication builtin topic: every writer discovered (``topic_name``,
        ``type_name`` as on DDS), each once, as :meth:`take` hands them over."""
        with _ENTITIES:
            return BuiltinDataReader(self.participant, BuiltinTopicDcpsPublication)

    def trigger_service(self, name: str, handler: Handler) -> Any:
        """The std_srvs/srv/Trigger service ``name`` on rmw_cyclonedds' wire
        (:class:`~omnibot.ros2.service.TriggerService`)."""
        from omnibot.ros2.service import TriggerService

        return TriggerService(self, name, handler)

    def declare(self, parameters: Sequence[Parameter]) -> None:
        """Keep ``parameters`` (this backend serves no parameter services: ``ros2 param`` cannot reach
        them)."""
        self.parameters.update({p.name: p for p in parameters})

    def service_endpoints(self, name: str, srv: str) -> tuple[Any, Any]:
        """The request reader and reply writer of the ROS service ``name`` of type ``srv``
        (``pkg/srv/Name``), as rmw_cyclonedds makes a service's: topics ``rq/<ns>/<name>Request`` and
        ``rr/<ns>/<name>Reply`` (:func:`~omnibot.ros2.types.request_type`), the services' default QoS
        (reliable, volatile, keep-last 10) and ``serviceid=<id>;`` in both USER_DATA (a client pairs
        them by it): the id is the participant's GUID prefix and a counter, formatted as rmw does."""
        self._services += 1
        guid = self.participant.guid.bytes[:12] + self._services.to_bytes(4, "big")
        csid = f"{guid[0]:2x}" + "".join(f".{b:x}" for b in guid[1:])
        user = f"serviceid={csid};"
        with _ENTITIES:
            requests, replies = self._service_endpoints(name, srv, user)
            self.readers.append(gid(requests))
            self.writers.append(gid(replies))
            self._announce()
        return requests, replies

    def _service_endpoints(self, name: str, srv: str, user: str) -> list[Any]:
        endpoints: list[Any] = []
        for kind, suffix, part, make in (
            ("rq", "Request", "_Request", DataReader),
            ("rr", "Reply", "_Response", DataWriter),
        ):
            typename = srv + part
            dds = topic_name(name, self.namespace, kind, suffix)
            topic = Topic(self.participant, dds, request_type(typename))
            self._topics[dds, typename] = topic
            endpoints.append(make(self.participant, topic, qos=qos(DEFAULT, typename, user)))
        return endpoints

    def close(self) -> None:
        """Release what was opened with the node (:attr:`closers`), then delete the participant (and
        everything it made)."""
        run_closers(self.closers)
        self._topics.clear()
        self._graph = None
        self.participant = None  # type: ignore[assignment]
