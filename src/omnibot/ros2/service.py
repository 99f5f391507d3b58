"""A ROS 2 service on cyclonedds, on rmw_cyclonedds' wire (ROS 2 services have no DDS standard).

rmw_cyclonedds (ros2/rmw_cyclonedds, ``rmw_node.cpp``, ``serdata.hpp``) carries a service on two
topics, ``rq/<ns>/<name>Request`` (client -> service) and ``rr/<ns>/<name>Reply`` (service -> client),
whose samples are the request or response message preceded by ``cdds_request_header_t``: ``guid``
(uint64: the client's request writer's instance handle) and ``seq`` (int64: the client's request
number). The service answers with the request's header unchanged; a client takes the replies whose
``guid`` is its own. Reader and writer carry ``serviceid=...;`` in USER_DATA so that a client's
``wait_for_service`` sees them as one service (:meth:`omnibot.ros2.dds.Node.service_endpoints`).

Other rmw implementations (rmw_fastrtps) put the request's identity in the RTPS inline QoS instead:
ROS 2 does not carry services across rmw vendors, so these services answer rmw_cyclonedds clients
(``RMW_IMPLEMENTATION=rmw_cyclonedds_cpp``) only; topics work with every rmw.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, Protocol

from omnibot.logs import schemas
from omnibot.ros2.types import dds_fields, request_type

TRIGGER = "std_srvs/srv/Trigger"


class Endpoints(Protocol):
    """What makes a service's endpoints (:meth:`omnibot.ros2.dds.Node.service_endpoints`)."""

    def service_endpoints(self, name: str, srv: str) -> tuple[Any, Any]:
        """The request reader and the reply writer of the service ``name`` of type ``srv``."""
        ...


def answer(replies: Any, request: Any, typename: str, **fields: Any) -> None:
    """Write the reply of ``typename`` (``pkg/srv/Name_Response``) with ``fields`` (rosbags' message
    values) to the request ``request`` on ``replies``, its header the request's, as rmw_cyclonedds
    answers."""
    reply: Any = request_type(typename)
    response = schemas.new(typename, **fields)
    replies.write(reply(guid=request.guid, seq=request.seq, **dds_fields(response, typename)))


class TriggerService:
    """A std_srvs/srv/Trigger service ``name``: :meth:`poll` answers every waiting request with
    ``handler()`` -> (success, message)."""

    def __init__(self, node: Endpoints, name: str, handler: Callable[[], tuple[bool, str]]) -> None:
        self.name = name
        self.handler = handler
        self.requests, self.replies = node.service_endpoints(name, TRIGGER)
        self.answered = 0

    def poll(self) -> int:
        """Answer the requests that arrived (without blocking); how many were answered."""
        count = 0
        for request in self.requests.take(N=16):
            if not hasattr(request, "guid"):
                continue  # a dispose or unregister: no data
            success, message = self.handler()
            answer(self.replies, request, TRIGGER + "_Response", success=success, message=message)
            count += 1
        self.answered += count
        return count
