"""The ends of the rclpy node (:mod:`omnibot.ros2.rclpy_backend`): a publisher of samples or CDR bytes
(:class:`RclpyWriter`), a raw subscription whose samples wait for the runtime (:class:`RclpyReader`),
the graph's publishers read as the ``dds`` backend reads DCPSPublication (:class:`GraphPublications`)
and a Trigger service answered in the runtime's thread (:class:`TriggerAnswers`).
"""

from __future__ import annotations

import collections
import importlib
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from omnibot.ros2.backend import Handler
from omnibot.ros2.dds import topic_name
from omnibot.ros2.types import dds_name, dds_type

_task: Any = importlib.import_module("rclpy.task")  # typed as Any: rclpy's typing is partial

GRAPH_PERIOD = 0.5
"""s between two readings of the graph by :meth:`~omnibot.ros2.rclpy_backend.RclpyNode.publications`."""


class RclpyWriter:
    """A publisher of cyclonedds samples or CDR bytes of ``typename``."""

    def __init__(self, publisher: Any) -> None:
        self.publisher = publisher

    def write(self, sample: Any) -> None:
        """Publish a cyclonedds sample (serialized, as rmw would)."""
        self.publisher.publish(bytes(sample.serialize()))

    def write_cdr(self, data: bytes) -> None:
        """Publish CDR bytes (with their encapsulation header) as they are."""
        self.publisher.publish(bytes(data))


class RclpyReader:
    """A raw subscription whose messages wait for :meth:`take` (keep-last: at most ``depth`` and 64)."""

    def __init__(self, typename: str, depth: int) -> None:
        self.type = dds_type(typename)
        self.queue: collections.deque[bytes] = collections.deque(maxlen=max(depth, 64))
        self._on_data: Callable[[], object] | None = None

    def __call__(self, data: bytes) -> None:
        """rclpy's callback: keep the message's bytes, then tell :meth:`on_data`'s callback."""
        self.queue.append(data)
        on_data = self._on_data
        if on_data is not None:
            on_data()

    def on_data(self, callback: Callable[[], object] | None) -> None:
        """Call ``callback()`` (in the executor's thread) after each message arrives; None: stop."""
        self._on_data = callback

    def take(self, N: int = 1) -> list[Any]:
        """At most ``N`` samples (cyclonedds', decoded from the CDR rclpy handed over), oldest first."""
        taken: list[Any] = []
        while len(taken) < N and self.queue:
            taken.append(self.type.deserialize(self.queue.popleft()))
        return taken


@dataclass(frozen=True)
class Publication:
    """A publisher in the graph, named as DCPSPublication names it."""

    topic_name: str
    type_name: str


class GraphPublications:
    """Every publisher rclpy's graph shows (each once), read at most every :data:`GRAPH_PERIOD` s."""

    def __init__(self, node: Any, clock: Callable[[], float] = time.monotonic) -> None:
        self.node = node
        self.clock = clock
        self.seen: set[tuple[str, str, bytes]] = set()
        self._last = -float("inf")

    def take(self, N: int = 1) -> list[Publication]:
        """The publishers not handed over before (at most ``N``)."""
        now = self.clock()
        if now - self._last < GRAPH_PERIOD:
            return []
        self._last = now
        found: list[Publication] = []
        for topic, _types in self.node.get_topic_names_and_types():
            for info in self.node.get_publishers_info_by_topic(topic):
                key = (topic, info.topic_type, bytes(info.endpoint_gid))
                if key in self.seen or len(found) >= N:
                    continue
                self.seen.add(key)
                found.append(Publication(topic_name(topic), dds_name(info.topic_type)))
        return found


class TriggerAnswers:
    """A std_srvs/srv/Trigger service: rclpy's callback (a coroutine) hands each request to
    :meth:`poll` (the runtime's thread) and awaits its answer."""

    def __init__(self, node: Any, executor: Any, srv: Any, name: str, handler: Handler) -> None:
        self.handler = handler
        self.executor = executor
        self.waiting: collections.deque[Any] = collections.deque()
        self.answered = 0
        self.service = node.create_service(srv, name, self._call)

    async def _call(self, request: Any, response: Any) -> Any:
        answer = _task.Future(executor=self.executor)
        answer.add_done_callback(_wake)  # its result then wakes the executor, which resumes this
        self.waiting.append(answer)
        response.success, response.message = await answer
        return response

    def poll(self) -> int:
        """Answer the requests that arrived (without blocking); how many were answered."""
        count = 0
        while self.waiting:
            self.waiting.popleft().set_result(self.handler())
            count += 1
        self.answered += count
        return count

    def close(self) -> None:
        """Answer what waits: no (the bridge is closing)."""
        while self.waiting:
            self.waiting.popleft().set_result((False, "the bridge is closing"))


def _wake(future: Any) -> None:
    """A done callback: scheduled on the executor, it wakes it."""
