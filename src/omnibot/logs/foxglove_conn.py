"""One Foxglove client's connection to :class:`~omnibot.logs.foxglove_ws.FoxgloveServer`: its
subscriptions, the channels it advertised (:class:`ClientChannel`, handed to a :class:`Publishing`),
the server's channels told to it (:class:`ServerChannel`) and its outgoing queues, bounded
(:data:`BACKLOG`) so that a client slow to read cannot hold the server's memory.
"""

from __future__ import annotations

import asyncio
import json
from collections import deque
from dataclasses import dataclass
from typing import Any, Protocol

from websockets.asyncio.server import ServerConnection

BACKLOG = 1024
"""Message data frames queued per client before the oldest are dropped (the SDK's default)."""


@dataclass(frozen=True)
class ClientChannel:
    """A channel a client advertised: its ``id`` (the client's), ``topic``, message ``encoding``
    and ``schema_name``."""

    id: int
    topic: str
    encoding: str
    schema_name: str


class Publishing(Protocol):
    """Where what clients publish goes; each method raises ValueError (its text goes to the client
    as an error status) to refuse."""

    def advertised(self, channel: ClientChannel) -> None:
        """A client advertised ``channel``."""

    def received(self, channel: ClientChannel, data: bytes) -> None:
        """A client published ``data`` on ``channel`` (called in the server's thread)."""


@dataclass(frozen=True)
class ServerChannel:
    """A channel of the server's (a topic it publishes), as advertised to its clients."""

    id: int
    topic: str
    schema_name: str
    schema: str

    def advert(self) -> dict[str, Any]:
        """The channel as the ``advertise`` operation lists it."""
        return {
            "id": self.id,
            "topic": self.topic,
            "encoding": "cdr",
            "schemaName": self.schema_name,
            "schema": self.schema,
            "schemaEncoding": "ros2msg",
        }


class Connection:
    """One connection: its subscriptions, its advertised channels, its outgoing queues."""

    def __init__(self, ws: ServerConnection) -> None:
        self.ws = ws
        self.subscriptions: dict[int, int] = {}
        """Subscription id -> channel id."""
        self.channels: dict[int, ClientChannel] = {}
        self.told: set[int] = set()
        """Server channels advertised to this client (each once, whichever of the greeting and a new
        topic's broadcast comes first: a topic new while the client connects is in both)."""
        self.control: deque[str] = deque()
        self.data: deque[bytes] = deque(maxlen=BACKLOG)
        self.ready = asyncio.Event()
        self.refused: set[int] = set()
        """Client channels whose refusal was logged (once each)."""
        self.overflow = False

    def send(self, frame: str) -> None:
        """Queue a control ``frame`` (JSON text); flag :attr:`overflow` when the queue is full."""
        if len(self.control) >= BACKLOG:  # not reading what it is told: cut off (the SDK's rule)
            self.overflow = True
            return
        self.control.append(frame)
        self.ready.set()

    def status(self, level: int, message: str) -> None:
        """Queue a ``status`` operation (``level`` 0 info, 1 warning, 2 error)."""
        self.send(json.dumps({"op": "status", "level": level, "message": message}))

    async def write_forever(self) -> None:
        """Send what is queued, control frames first, as it comes (until the connection ends)."""
        while True:
            await self.ready.wait()
            self.ready.clear()
            while self.control or self.data:
                await self.ws.send(self.control.popleft() if self.control else self.data.popleft())


def u32_ids(items: Any, key: str) -> list[int] | None:
    """``items`` (a list; of objects: their ``key``) as u32 ids; None when any is not one."""
    if not isinstance(items, list):
        return None
    values = [item.get(key) if isinstance(item, dict) else None for item in items] if key else items
    ids = [v for v in values if isinstance(v, int) and not isinstance(v, bool) and 0 <= v < 2**32]
    return ids if len(ids) == len(values) else None
