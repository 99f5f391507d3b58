"""``--foxglove [HOST:]PORT``: the recorder's messages served live through the Foxglove SDK's
WebSocket server (``foxglove-sdk``), the same channels and ROS 2 schemas as the log file, so Foxglove
shows a running robot as it shows a recorded one; and Foxglove's Teleop panel as a command source.

Binding: 127.0.0.1 by default, with no token, as the SDK's server is. Bound to any other address
(``--foxglove 0.0.0.0:8765``) it takes commands that move the robot from the network, so it requires
an access token, as the dashboard does and with the dashboard's code
(:func:`omnibot.web.access.access_token`: the one given with ``--foxglove-token`` or
``$OMNIBOT_FOXGLOVE_TOKEN``, else a random one, printed in the URL). The SDK's server has no way to
check one, nor does it accept the old name of its subprotocol (``foxglove.websocket.v1``, which
Lichtblick and ws-protocol's clients speak), so it always listens on 127.0.0.1 on a port of its own
behind a :class:`~omnibot.logs.gate.TokenGate`, which relays only the connections whose URL carries
the token (``ws://HOST:PORT/?token=TOKEN``; every one without a token) and offers the old name as
the new. A token given on loopback is required there too.

Client publish: a Foxglove client may advertise ``cmd_vel`` (or ``/cmd_vel``) with a
``geometry_msgs/Twist`` schema (``geometry_msgs/msg/Twist`` too) in ``cdr`` or ``json``, as the
Teleop panel does; each message is handed to the :class:`PanelSource`, a source of the runtime's
arbitration (priority 30: under the page's stick, over the follower) that stops the robot when the
panel stops publishing for :data:`PANEL_HOLD` s.
"""

from __future__ import annotations

import json
import logging
import threading
from typing import Any

from foxglove.websocket import Capability, Client, ClientChannel, ServerListener

from omnibot.errors import ConfigError
from omnibot.logs import schemas
from omnibot.logs.gate import TokenGate
from omnibot.logs.topics import TELEOP
from omnibot.motion import Twist
from omnibot.runtime.cycle import Cycle
from omnibot.runtime.sources import Proposal

DEFAULT_PORT = 8765
HOST = "127.0.0.1"
PANEL_PRIORITY = 30
"""Between the page's stick (100) and the follower (10)."""
PANEL_HOLD = 0.5
"""s: a panel's twist is held this long (the Teleop panel publishes at its rate, 10 Hz in the
shipped layout); then one zero twist, then silence."""
TWIST_SCHEMAS = {"geometry_msgs/Twist", "geometry_msgs/msg/Twist"}

log = logging.getLogger("omnibot.logs")


class PanelSource:
    """Foxglove's Teleop panel as a runtime source: :meth:`put` (any thread) the newest twist;
    :meth:`propose` drives it for :data:`PANEL_HOLD` s of the cycle clock after it arrived, then
    proposes one zero twist (a stop) and falls silent until the next message."""

    def __init__(
        self, *, name: str = "foxglove", priority: int = PANEL_PRIORITY, hold: float = PANEL_HOLD
    ) -> None:
        self.name = name
        self.priority = priority
        self.hold = hold
        self.timeout = hold
        self.watchdog = 0.25
        self.received = 0
        """Twists received from clients so far."""
        self._lock = threading.Lock()
        self._newest: Twist | None = None
        self._seen = 0
        self._since: float | None = None
        self._twist: Twist | None = None

    def put(self, twist: Twist) -> None:
        """A client published ``twist``."""
        with self._lock:
            self._newest = twist
            self.received += 1

    def propose(self, cycle: Cycle) -> Proposal | None:
        """The panel's newest twist while it is fresh; a zero twist once when it is not."""
        with self._lock:
            count, newest = self.received, self._newest
        if count != self._seen and newest is not None:
            self._seen, self._since, self._twist = count, cycle.now, newest
        if self._since is None or self._twist is None:
            return None
        if cycle.now - self._since <= self.hold:
            return Proposal(self._twist)
        self._since = self._twist = None
        return Proposal(Twist())


def decode_twist(encoding: str, data: bytes) -> Twist:
    """A geometry_msgs/Twist as a client sends it (``cdr`` or ``json``); ValueError if it is not one."""
    if encoding == "json":
        msg = json.loads(data)
        lin, ang = msg.get("linear", {}), msg.get("angular", {})
        return Twist(float(lin.get("x", 0.0)), float(lin.get("y", 0.0)), float(ang.get("z", 0.0)))
    if encoding == "cdr":
        msg = schemas.deserialize(data, "geometry_msgs/msg/Twist")
        return Twist(float(msg.linear.x), float(msg.linear.y), float(msg.angular.z))
    raise ValueError(f"encoding {encoding!r} (expected cdr or json)")


class _Listener(ServerListener):
    """The SDK's server listener: client-published twists on :data:`TELEOP` go to the panel source
    (the channels a client advertises are remembered by client and channel id)."""

    def __init__(self, panel: PanelSource) -> None:
        self.panel = panel
        self._channels: dict[tuple[int, int], ClientChannel] = {}

    def on_client_advertise(self, client: Client, channel: ClientChannel) -> None:
        if channel.topic.lstrip("/") != TELEOP or channel.schema_name not in TWIST_SCHEMAS:
            log.warning("Foxglove client publishes %s (%s): ignored", channel.topic, channel.schema_name)
            return
        self._channels[(client.id, channel.id)] = channel

    def on_client_unadvertise(self, client: Client, client_channel_id: int) -> None:
        self._channels.pop((client.id, client_channel_id), None)

    def on_message_data(self, client: Client, client_channel_id: int, data: bytes) -> None:
        channel = self._channels.get((client.id, client_channel_id))
        if channel is None:
            return
        try:
            twist = decode_twist(channel.encoding, bytes(data))
        except Exception as exc:  # a client's bad message must not reach the robot loop
            log.warning("Foxglove client's %s: cannot decode: %s", channel.topic, exc)
            return
        self.panel.put(twist)


def parse_address(text: str | int) -> tuple[str, int]:
    """``--foxglove``'s ``[HOST:]PORT`` (``8765``, ``0.0.0.0:8765``, ``[::1]:8765``, ``robot.local:0``)
    as (host, port); the host is 127.0.0.1 when left out. ConfigError when it is neither."""
    value = str(text).strip()
    if value.isdigit():
        host, port = HOST, value
    elif value.startswith("["):  # [IPv6]:PORT
        end = value.find("]:")
        host, port = (value[1:end], value[end + 2 :]) if end > 0 else ("", "")
    else:
        host, sep, port = value.rpartition(":")
        if not sep or ":" in host:  # an IPv6 address needs its brackets
            host = ""
    if not host or not port.isdigit() or not 0 <= int(port) <= 65535:
        raise ConfigError(
            f"expected [HOST:]PORT with a port 0..65535 (0: any free one), e.g. 8765 or 0.0.0.0:8765; "
            f"got {value!r}",
            key="--foxglove",
        )
    return host, int(port)


class FoxgloveLive:
    """A Foxglove WebSocket server on ``host:port`` (0: a free port, see :attr:`port`; off loopback or
    with a ``token``, behind a :class:`~omnibot.logs.gate.TokenGate`: see the module docstring); call
    it as a recorder mirror, ``live(topic, typename, cdr_bytes, ns)``; :attr:`panel` is the Teleop
    panel's source (a runtime adds it); :attr:`url` is where to connect; :meth:`close` stops it."""

    def __init__(
        self, port: int = DEFAULT_PORT, *, host: str = HOST, token: str | None = None, name: str = "omnibot"
    ) -> None:
        import foxglove

        from omnibot.web.access import access_token

        self.host = host
        self.token = access_token(host, token, key="--foxglove-token")
        self._foxglove = foxglove
        self._context = foxglove.Context()
        self.panel = PanelSource()
        try:  # on 127.0.0.1, behind the gate (the token, the old subprotocol)
            self._server = foxglove.start_server(
                name=name,
                host=HOST,
                port=0,
                context=self._context,
                capabilities=[Capability.ClientPublish],
                supported_encodings=["cdr", "json"],
                server_listener=_Listener(self.panel),
            )
        except Exception as exc:  # the SDK raises its own error for a port in use
            raise ConfigError(f"cannot serve Foxglove on {host}:{port}: {exc}", key="--foxglove") from None
        try:
            self._gate = TokenGate(host, port, self._server.port, self.token)
        except BaseException:
            self._server.stop()
            raise
        self.port: int = self._gate.port
        self._channels: dict[str, Any] = {}

    @property
    def url(self) -> str:
        """Where a Foxglove client connects (with ``?token=`` when one is required)."""
        host = f"[{self.host}]" if ":" in self.host else self.host
        query = f"?token={self.token}" if self.token else ""
        return f"ws://{host}:{self.port}/{query}"

    def __call__(self, topic: str, typename: str, data: bytes, ns: int) -> None:
        """Publish one recorded message (CDR ``data`` of ``typename``) on ``topic``, its channel made
        on first use."""
        channel = self._channels.get(topic)
        if channel is None:
            schema = self._foxglove.Schema(
                name=typename, encoding="ros2msg", data=schemas.schema_text(typename).encode("utf-8")
            )
            channel = self._foxglove.Channel(
                topic, schema=schema, message_encoding="cdr", context=self._context
            )
            self._channels[topic] = channel
        channel.log(data, log_time=ns)

    def close(self) -> None:
        """Close every channel and stop the server."""
        for channel in self._channels.values():
            channel.close()
        self._channels.clear()
        self._gate.close()
        self._server.stop()
