"""The bridge as a genuine rclpy node (``--ros-backend rclpy``): the user's rmw, the ROS graph's node,
parameters and services (:mod:`omnibot.ros2.backend` for the interface).

* one rclpy context per process (robots of one process are nodes of it, ``/r1/omnibot``...), spun
  by a single-threaded executor in a thread of its own: subscriptions queue what arrives for the
  runtime's :meth:`take`; a service's callback is a coroutine that hands its request to the
  runtime's :meth:`poll` and awaits the answer (the executor goes on with topics and parameters
  meanwhile);
* publishing is serialized: a writer publishes CDR bytes (``Publisher.publish(bytes)``, rclpy's
  ``publish_raw``), the recorder's as they are or a sample's ``serialize()``; subscriptions are
  ``raw`` and their bytes become the same cyclonedds samples the ``dds`` backend hands over;
* the bridge's options are ROS parameters (:meth:`declare`): read-only ones are refused by rclpy
  with its reason, writable ones by their own check; ``use_sim_time`` is rclpy's, true on a
  simulator (the node's clock follows the ``/clock`` the bridge publishes);
* a type whose rclpy package cannot be imported here (the PyPI ROS wheels have no tf2_msgs; std_srvs
  and diagnostic_msgs are wheels of their own) goes on the DDS wire instead, through a companion
  ``dds`` node ``<name>_wire`` beside it (:mod:`omnibot.ros2.dds`, announced in the graph too),
  said once per type;
* :meth:`publications` reads the graph (at most every
  :data:`~omnibot.ros2.rclpy_endpoints.GRAPH_PERIOD` s) as the ``dds`` backend reads DCPSPublication
  (the node's ends: :mod:`omnibot.ros2.rclpy_endpoints`).

Under pytest the node is refused outside a private network namespace, as a DDS participant is.
"""

from __future__ import annotations

import importlib
import logging
import os
import threading
from collections.abc import Callable, Mapping, Sequence
from typing import Any

from omnibot.ros2 import netns
from omnibot.ros2.backend import DEFAULT, NODE_NAME, Handler, Parameter, Profile, run_closers
from omnibot.ros2.dds import discovery_range
from omnibot.ros2.rclpy_endpoints import GraphPublications, RclpyReader, RclpyWriter, TriggerAnswers


def _load(module: str) -> Any:
    """A module of rclpy's (typed as Any: rclpy's typing is partial, and absent where it is)."""
    return importlib.import_module(module)


_context: Any = _load("rclpy.context")
_executors: Any = _load("rclpy.executors")
_node: Any = _load("rclpy.node")
_parameter: Any = _load("rclpy.parameter")
_qos: Any = _load("rclpy.qos")
_interfaces: Any = _load("rcl_interfaces.msg")


log = logging.getLogger("omnibot.ros2")

TRIGGER = "std_srvs/srv/Trigger"


def message_class(typename: str) -> Any:
    """rclpy's class of the ROS type ``typename`` (``pkg/msg/Name``, ``pkg/srv/Name``); None when its
    package cannot be imported here."""
    pkg, kind, name = typename.split("/")
    try:
        return getattr(importlib.import_module(f"{pkg}.{kind}"), name)
    except (ImportError, AttributeError):
        return None


def qos_profile(profile: Profile) -> Any:
    """rclpy's QoS of ``profile``."""
    return _qos.QoSProfile(
        history=_qos.HistoryPolicy.KEEP_LAST,
        depth=profile.depth,
        reliability=_qos.ReliabilityPolicy.RELIABLE
        if profile.reliable
        else _qos.ReliabilityPolicy.BEST_EFFORT,
        durability=_qos.DurabilityPolicy.TRANSIENT_LOCAL
        if profile.transient_local
        else _qos.DurabilityPolicy.VOLATILE,
    )


class _Spinner:
    """An rclpy context with one executor spinning its nodes in a thread of its own, shared by the
    process's nodes (:func:`_spinner`): ``level`` 0 is the nodes', 1 and up their helpers' (Fast DDS
    takes one type per topic name in a participant, and a context is a participant)."""

    def __init__(self) -> None:
        self.users = 0
        self.context = _context.Context()
        self.context.init()
        self.executor = _executors.SingleThreadedExecutor(context=self.context)
        self.thread = threading.Thread(target=self._spin, name="omnibot-rclpy", daemon=True)
        self.thread.start()

    def _spin(self) -> None:
        try:
            self.executor.spin()
        except Exception:  # the context shut down under it
            log.debug("rclpy executor ended", exc_info=True)

    def close(self) -> None:
        self.executor.shutdown(timeout_sec=2.0)
        self.context.try_shutdown()
        self.thread.join(timeout=5.0)


_SPINNERS: dict[int, _Spinner] = {}
_SPINNERS_LOCK = threading.Lock()


def _acquire(level: int) -> _Spinner:
    with _SPINNERS_LOCK:
        spinner = _SPINNERS.get(level)
        if spinner is None:
            spinner = _SPINNERS[level] = _Spinner()
        spinner.users += 1
        return spinner


def _release(level: int) -> None:
    with _SPINNERS_LOCK:
        spinner = _SPINNERS[level]
        spinner.users -= 1
        if not spinner.users:
            del _SPINNERS[level]
            spinner.close()


class RclpyNode:
    """The bridge's rclpy node ``name`` in ``namespace`` (see the module docstring)."""

    backend = "rclpy"

    def __init__(
        self,
        namespace: str = "",
        *,
        name: str = NODE_NAME,
        sim_time: bool = False,
        env: Mapping[str, str] | None = None,
    ) -> None:
        env = os.environ if env is None else env
        netns.check_participant_allowed()
        self.name = name
        self.namespace = namespace.strip("/")
        self.scope = discovery_range(env)
        self.closers: list[Callable[[], object]] = []
        self.parameters: dict[str, Parameter] = {}
        self._closed = False
        self._nodes: list[tuple[int, Any]] = []
        """The node, then its helpers (one per extra type on a topic name), each at its level."""
        self._types: dict[str, list[str]] = {}
        """The types of each topic name, in the order their endpoints were made."""
        self._wire: Any = None
        self.wired: list[str] = []
        """The types that went on the DDS wire (no rclpy package here)."""
        self.node = self._node(0, name, sim_time)
        self.domain_id = int(self.node.context.get_domain_id())
        self.node.add_on_set_parameters_callback(self._on_set)
        self.node.add_post_set_parameters_callback(self._on_done)

    def _node(self, level: int, name: str, sim_time: bool = False) -> Any:
        """A node at ``level`` (its spinner's), spun from now on."""
        spinner = _acquire(level)
        try:
            node = _node.Node(
                name,
                namespace="/" + self.namespace,
                context=spinner.context,
                parameter_overrides=[_parameter.Parameter("use_sim_time", value=sim_time)],
            )
        except BaseException:
            _release(level)
            raise
        spinner.executor.add_node(node)
        self._nodes.append((level, node))
        return node

    def _holder(self, topic: str, typename: str) -> Any:
        """The node to make an endpoint of ``typename`` on ``topic`` in: the node, or for a second type
        on one topic name a helper node (``omnibot_twist``) in a context of its own."""
        types = self._types.setdefault(topic, [])
        if typename not in types:
            types.append(typename)
        level = types.index(typename)
        if level == 0:
            return self.node
        for at, node in self._nodes:
            if at == level:
                return node
        return self._node(level, f"{self.name}_{typename.rsplit('/', 1)[1].lower()}")

    @property
    def fully_qualified_name(self) -> str:
        """``/r1/omnibot``."""
        return str(self.node.get_fully_qualified_name())

    def wire(self, typename: str, why: str = "") -> Any:
        """The companion ``dds`` node, for ``typename`` that rclpy cannot carry here, or ``why`` it goes on
        the wire anyway (said once)."""
        from omnibot.ros2.dds import Node as WireNode

        if typename not in self.wired:
            self.wired.append(typename)
            log.warning(
                "%s: %s: it goes on the DDS wire (node %s_wire)",
                self.fully_qualified_name,
                why or f"no rclpy package for {typename} here",
                self.name,
            )
        if self._wire is None:
            self._wire = WireNode(self.namespace, name=f"{self.name}_wire")
        return self._wire

    def writer(self, name: str, typename: str, profile: Profile = DEFAULT) -> Any:
        """A publisher of ``typename`` on ``name`` (serialized)."""
        cls = message_class(typename)
        if cls is None:
            return self.wire(typename).writer(name, typename, profile)
        holder = self._holder(name, typename)
        return RclpyWriter(holder.create_publisher(cls, name, qos_profile(profile)))

    def reader(self, name: str, typename: str, profile: Profile = DEFAULT) -> Any:
        """A raw subscription of ``typename`` on ``name``."""
        cls = message_class(typename)
        if cls is None:
            return self.wire(typename).reader(name, typename, profile)
        reader = RclpyReader(typename, profile.depth)
        holder = self._holder(name, typename)
        holder.create_subscription(cls, name, reader, qos_profile(profile), raw=True)
        return reader

    def publications(self) -> GraphPublications:
        """The publishers of the graph, each once (see :class:`GraphPublications`)."""
        return GraphPublications(self.node)

    def trigger_service(self, name: str, handler: Handler) -> Any:
        """The std_srvs/srv/Trigger service ``name`` on the node's rmw (on the DDS wire, for
        rmw_cyclonedds clients only, where std_srvs cannot be imported)."""
        srv = message_class(TRIGGER)
        if srv is None:
            return self.wire(TRIGGER).trigger_service(name, handler)
        service = TriggerAnswers(self.node, self.node.executor, srv, name, handler)
        self.closers.insert(0, service.close)
        return service

    def declare(self, parameters: Sequence[Parameter]) -> None:
        """Declare ``parameters`` as ROS parameters (read-only ones with ``read_only`` set)."""
        for p in parameters:
            self.parameters[p.name] = p
            descriptor = _interfaces.ParameterDescriptor(description=p.description, read_only=p.read_only)
            self.node.declare_parameter(p.name, p.value, descriptor)

    def _on_set(self, changes: list[Any]) -> Any:
        """rclpy's check of new values: the writable parameters' ``check`` says yes or why not."""
        for change in changes:
            known = self.parameters.get(change.name)
            if known is None or known.check is None:
                continue  # rclpy's own (use_sim_time) or refused by rclpy as read-only
            why = known.check(change.value)
            if why is not None:
                return _interfaces.SetParametersResult(successful=False, reason=f"{change.name}: {why}")
        return _interfaces.SetParametersResult(successful=True)

    def _on_done(self, changes: list[Any]) -> None:
        """rclpy set the new values (all admitted): put them in force."""
        for change in changes:
            known = self.parameters.get(change.name)
            if known is not None:
                known.assign(change.value)

    def close(self) -> None:
        """Release what was opened with the node, then the node (and the context with the last)."""
        if self._closed:
            return
        self._closed = True
        run_closers(self.closers)
        if self._wire is not None:
            self._wire.close()
            self._wire = None
        for level, node in reversed(self._nodes):
            _SPINNERS[level].executor.remove_node(node)
            node.destroy_node()
            _release(level)
        self._nodes.clear()
