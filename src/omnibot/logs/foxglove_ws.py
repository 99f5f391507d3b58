"""The Foxglove WebSocket protocol, server side: what Foxglove live needs of it, on one port, under
the dashboard's access rules.

The Foxglove SDK's own server accepts every client that speaks its subprotocol (its handshake checks
neither ``Host`` nor ``Origin`` nor any token, and its listener hears of a client only when it
subscribes or publishes, too late to refuse it), so any web page could drive the robot through it,
and a gate in front of it still left the SDK's own port open on 127.0.0.1. This server checks every
upgrade request before it is accepted, with :mod:`omnibot.web.access` (the dashboard's code):

* ``Host`` must name this server (:class:`~omnibot.web.access.HostPolicy`; DNS rebinding);
* ``Origin``, when there is one (a browser), must be this server or one of ``origins``
  (:data:`FOXGLOVE_APP`, Foxglove's web app, by default); ``null`` never is;
* the access token, when one is set, as ``?token=`` (compared in constant time);
* at most :data:`MAX_CLIENTS` at once.

A refused request gets ``403`` (``503`` when full) and never reaches the protocol. Both names of the
subprotocol are spoken: ``foxglove.sdk.v1`` and its old name ``foxglove.websocket.v1`` (Lichtblick
and ws-protocol's clients), answered with the name the client offered.

The protocol (Foxglove's ws-protocol, spec v1), the part spoken here::

    server -> client  text    serverInfo            on connect: name, capabilities, encodings
                              advertise             channels {id, topic, encoding, schemaName,
                                                    schema, schemaEncoding}, on connect and when new
                              status                {level 0 info | 1 warning | 2 error, message}:
                                                    why a client's message was refused
                      binary  0x01 message data     u8 op | u32 subscription id | u64 log time ns |
                                                    payload   (little-endian)
    client -> server  text    subscribe             {subscriptions: [{id, channelId}]}
                              unsubscribe           {subscriptionIds: [id]}
                              advertise             {channels: [{id, topic, encoding, schemaName}]}
                              unadvertise           {channelIds: [id]}
                      binary  0x01 message data     u8 op | u32 client channel id | payload

A client's message that breaks the protocol is answered with a ``status`` and otherwise ignored;
what a client publishes goes to a :class:`~omnibot.logs.foxglove_conn.Publishing` (which may refuse it: the client gets its
reason as an error status). More than :data:`RATE` messages a second (bursts :data:`BURST`) close
the connection (1008); frames over :data:`MAX_FRAME` bytes too (1009). A client slow to read loses
the oldest message data beyond :data:`~omnibot.logs.foxglove_conn.BACKLOG` per connection, and is cut off (1008) when as many
control messages (adverts, statuses) wait for it.

The server runs its own asyncio loop in a thread (``omnibot-foxglove``), started by the constructor
(which binds the port: a port in use fails at once) and stopped by :meth:`FoxgloveServer.close`.
:meth:`FoxgloveServer.publish` may be called from any thread.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import logging
import struct
import threading
import time
from collections import deque
from http import HTTPStatus
from typing import Any
from urllib.parse import parse_qs, urlsplit

from websockets.asyncio.server import Server, ServerConnection, serve
from websockets.datastructures import MultipleValuesError
from websockets.exceptions import ConnectionClosed
from websockets.http11 import Request, Response
from websockets.typing import Subprotocol

from omnibot.errors import ConfigError
from omnibot.logs.foxglove_conn import BACKLOG, ClientChannel, Connection, Publishing, ServerChannel, u32_ids
from omnibot.web import HostPolicy, RateLimit, listening_socket, same_origin, token_ok

SDK_SUBPROTOCOL = "foxglove.sdk.v1"
OLD_SUBPROTOCOL = "foxglove.websocket.v1"
FOXGLOVE_APP = ("https://app.foxglove.dev",)
"""Origins allowed besides the server's own: Foxglove's web app."""
MAX_CLIENTS = 16
MAX_FRAME = 65536
"""Bytes a client's frame may have (a twist is about 100)."""
RATE = 100.0
"""Messages a second one client may send on average (the Teleop panel sends 10-20)."""
BURST = 200
HANDSHAKE_TIMEOUT = 5.0
MESSAGE_DATA = 0x01
CLOSE_POLICY = 1008
REFUSED_TOKEN = (
    "This server needs its access token: ws://HOST:PORT/?token=TOKEN (printed where it started).\n"
)
REFUSED_HOST = "The Host header names a server this is not (DNS rebinding?).\n"
REFUSED_ORIGIN = "A page of another site may not connect to this server.\n"

log = logging.getLogger("omnibot.logs")


class FoxgloveServer:
    """The Foxglove WebSocket protocol on ``host:port`` (0: a free one, see :attr:`port`) with the
    access rules of the module docstring; what clients publish goes to ``publishing``;
    :attr:`refused` counts the upgrade requests refused, :attr:`clients` the clients connected."""

    def __init__(
        self,
        host: str,
        port: int,
        publishing: Publishing,
        *,
        token: str | None = None,
        name: str = "omnibot",
        origins: tuple[str, ...] = FOXGLOVE_APP,
        key: str = "--foxglove",
    ) -> None:
        self.name = name
        self.token = token
        self.origins = frozenset(o.rstrip("/").lower() for o in origins)
        self.publishing = publishing
        self.refused = 0
        self._told: set[str] = set()
        self._sock = listening_socket(host, port, host_key=key, port_key=key, backlog=16)
        self.port: int = self._sock.getsockname()[1]
        self.policy = HostPolicy.for_bind(host, self.port)
        self._lock = threading.Lock()
        self._channels: dict[str, ServerChannel] = {}
        self._subscribed: frozenset[int] = frozenset()
        """Channel ids some client subscribes to (replaced whole, read from any thread)."""
        self._clients: set[Connection] = set()
        self._queue: deque[tuple[int, int, bytes]] = deque(maxlen=4 * BACKLOG)
        """Messages published for subscribers, not yet handed to their connections."""
        self._woken = False
        self._loop: asyncio.AbstractEventLoop | None = None
        self._stop: asyncio.Event | None = None
        self._ready = threading.Event()
        self._failed: BaseException | None = None
        self._thread = threading.Thread(target=self._run, name="omnibot-foxglove", daemon=True)
        self._thread.start()
        self._ready.wait()
        if self._failed is not None:
            self._thread.join()
            self._sock.close()
            raise ConfigError(f"cannot serve on {host}:{port}: {self._failed}", key=key)

    @property
    def clients(self) -> int:
        """Clients connected now."""
        return len(self._clients)

    # ----------------------------------------------------------------------- any thread
    def publish(self, topic: str, schema_name: str, schema: str, data: bytes, ns: int) -> None:
        """Send ``data`` (CDR of ``schema_name``, whose ros2msg text is ``schema``) logged at ``ns`` on
        ``topic`` to its subscribers; a new topic is advertised to every client first."""
        channel = self._channels.get(topic)
        if channel is None:
            with self._lock:
                channel = self._channels.get(topic)
                if channel is None:
                    channel = ServerChannel(len(self._channels) + 1, topic, schema_name, schema)
                    self._channels[topic] = channel
                    self._call(self._advertise, channel)
        if channel.id in self._subscribed:
            with self._lock:  # the loop is woken once for what a burst publishes
                self._queue.append((channel.id, ns, data))
                wake, self._woken = not self._woken, True
            if wake:
                self._call(self._flush)

    def _call(self, fn: Any, *args: Any) -> None:
        loop = self._loop
        if loop is not None:
            with contextlib.suppress(RuntimeError):  # the loop has ended: nobody to send to
                loop.call_soon_threadsafe(fn, *args)

    def close(self) -> None:
        """Close every connection and stop listening (idempotent)."""
        loop, stop = self._loop, self._stop
        if loop is not None and stop is not None and self._thread.is_alive():
            with contextlib.suppress(RuntimeError):
                loop.call_soon_threadsafe(stop.set)
            self._thread.join(timeout=10.0)
        self._sock.close()

    # ----------------------------------------------------------------------- the server's thread
    def _run(self) -> None:
        try:
            asyncio.run(self._main())
        except BaseException as exc:  # before serving: the constructor reports it
            self._failed = exc
        finally:
            self._ready.set()

    async def _main(self) -> None:
        self._loop = asyncio.get_running_loop()
        self._stop = asyncio.Event()
        server: Server = await serve(
            self._serve,
            sock=self._sock,
            subprotocols=[Subprotocol(SDK_SUBPROTOCOL), Subprotocol(OLD_SUBPROTOCOL)],
            process_request=self._check,
            compression=None,
            max_size=MAX_FRAME,
            open_timeout=HANDSHAKE_TIMEOUT,
            close_timeout=2.0,
            server_header=None,
            logger=logging.getLogger("omnibot.logs.foxglove_ws"),
        )
        self._ready.set()
        try:
            await self._stop.wait()
        finally:
            server.close()
            await server.wait_closed()

    def _check(self, connection: ServerConnection, request: Request) -> Response | None:
        """The access rules (module docstring): None lets the handshake go on."""
        try:
            host = request.headers.get("Host")
            origin = request.headers.get("Origin")
        except MultipleValuesError:
            host = origin = "\n"  # two of either: refused below
        why = None
        if not self.policy.allows(host):
            why = REFUSED_HOST
        elif not self._origin_ok(origin, host):
            why = REFUSED_ORIGIN
        elif not token_ok(self.token, _token(request.path)):
            why = REFUSED_TOKEN
        if why is not None:
            self.refused += 1
            level = logging.DEBUG if why in self._told else logging.WARNING  # each reason once
            self._told.add(why)
            log.log(
                level, "Foxglove live refused a client (Host %r, Origin %r): %s", host, origin, why.strip()
            )
            return connection.respond(HTTPStatus.FORBIDDEN, why)
        if len(self._clients) >= MAX_CLIENTS:
            self.refused += 1
            return connection.respond(HTTPStatus.SERVICE_UNAVAILABLE, "Too many clients.\n")
        return None

    def _origin_ok(self, origin: str | None, host: str | None) -> bool:
        if origin is None:
            return True  # not a browser
        return origin.rstrip("/").lower() in self.origins or (origin != "null" and same_origin(origin, host))

    async def _serve(self, ws: ServerConnection) -> None:
        client = Connection(ws)
        self._clients.add(client)
        writer = asyncio.create_task(client.write_forever())
        budget = RateLimit(RATE, BURST)
        try:
            client.send(
                json.dumps(
                    {
                        "op": "serverInfo",
                        "name": self.name,
                        "capabilities": ["clientPublish"],
                        "supportedEncodings": ["cdr", "json"],
                        "metadata": {},
                        "sessionId": f"{self.name}-{time.time_ns()}",
                    }
                )
            )
            with self._lock:
                channels = list(self._channels.values())
            if channels:
                client.told.update(c.id for c in channels)
                client.send(json.dumps({"op": "advertise", "channels": [c.advert() for c in channels]}))
            async for message in ws:
                if not budget.take():
                    await ws.close(CLOSE_POLICY, f"too many messages (at most {RATE:g} a second)")
                    break
                if isinstance(message, str):
                    self._text(client, message)
                else:
                    self._binary(client, message)
                if client.overflow:
                    await ws.close(CLOSE_POLICY, "not reading: too many messages waiting for it")
                    break
        except ConnectionClosed:
            pass
        finally:
            writer.cancel()
            with contextlib.suppress(asyncio.CancelledError, ConnectionClosed):
                await writer
            self._clients.discard(client)
            self._resubscribed()

    def _text(self, client: Connection, message: str) -> None:
        try:
            msg = json.loads(message)
        except (ValueError, RecursionError):  # not JSON, or nested too deeply
            msg = None
        op = msg.get("op") if isinstance(msg, dict) else None
        if op == "subscribe":
            subs = msg.get("subscriptions") if isinstance(msg, dict) else None
            ids, chans = u32_ids(subs, "id"), u32_ids(subs, "channelId")
            with self._lock:
                known = {c.id for c in self._channels.values()}
            if ids is None or chans is None or not set(chans) <= known:
                client.status(2, "subscribe: expected subscriptions [{id, channelId}] of advertised channels")
                return
            client.subscriptions.update(zip(ids, chans, strict=True))
        elif op == "unsubscribe":
            ids = u32_ids(msg.get("subscriptionIds") if isinstance(msg, dict) else None, "")
            if ids is None:
                client.status(2, "unsubscribe: expected subscriptionIds [id]")
                return
            for sid in ids:
                client.subscriptions.pop(sid, None)
        elif op == "advertise":
            self._advertised(client, msg.get("channels") if isinstance(msg, dict) else None)
        elif op == "unadvertise":
            ids = u32_ids(msg.get("channelIds") if isinstance(msg, dict) else None, "")
            for cid in ids or []:
                client.channels.pop(cid, None)
        else:
            client.status(
                1,
                f"unsupported message {str(op)[:40]!r} (this server speaks subscribe, "
                "unsubscribe, advertise, unadvertise)"
                if op
                else "expected a JSON object with an op",
            )
            return
        self._resubscribed()

    def _advertised(self, client: Connection, channels: Any) -> None:
        ids = u32_ids(channels, "id")
        if ids is None:
            client.status(2, "advertise: expected channels [{id, topic, encoding, schemaName}]")
            return
        for item in channels:
            fields = [item.get(k) for k in ("topic", "encoding", "schemaName")]
            if not all(isinstance(f, str) for f in fields):
                client.status(
                    2, f"advertise: channel {item['id']} needs topic, encoding, schemaName (strings)"
                )
                continue
            channel = ClientChannel(item["id"], *fields)
            try:
                self.publishing.advertised(channel)
            except ValueError as exc:
                client.status(1, f"{channel.topic}: {exc}")
                log.warning(
                    "Foxglove client publishes %s (%s): ignored, %s", channel.topic, channel.schema_name, exc
                )
                continue
            client.channels[channel.id] = channel

    def _binary(self, client: Connection, message: bytes) -> None:
        if len(message) < 5 or message[0] != MESSAGE_DATA:
            client.status(2, "expected binary message data: 0x01, u32 channel id, payload")
            return
        (cid,) = struct.unpack_from("<I", message, 1)
        channel = client.channels.get(cid)
        if channel is None:
            client.status(2, f"message data on channel {cid}, which this client did not advertise")
            return
        try:
            self.publishing.received(channel, bytes(message[5:]))
        except ValueError as exc:
            client.status(2, f"{channel.topic}: message refused, not driven: {exc}")
            if cid not in client.refused:
                client.refused.add(cid)
                log.warning("Foxglove client's %s: message refused: %s", channel.topic, exc)

    def _resubscribed(self) -> None:
        self._subscribed = frozenset(c for client in self._clients for c in client.subscriptions.values())

    def _advertise(self, channel: ServerChannel) -> None:
        frame = json.dumps({"op": "advertise", "channels": [channel.advert()]})
        for client in self._clients:
            if channel.id not in client.told:
                client.told.add(channel.id)
                client.send(frame)

    def _flush(self) -> None:
        with self._lock:
            queued = list(self._queue)
            self._queue.clear()
            self._woken = False
        for channel_id, ns, data in queued:
            for client in self._clients:
                for sid, cid in client.subscriptions.items():
                    if cid == channel_id:
                        client.data.append(struct.pack("<BIQ", MESSAGE_DATA, sid, ns) + data)
                        client.ready.set()


def _token(path: str) -> str | None:
    """The ``token`` query parameter of a request path (None: none, or not exactly one)."""
    values = parse_qs(urlsplit(path).query).get("token", [])
    return values[0] if len(values) == 1 else None
