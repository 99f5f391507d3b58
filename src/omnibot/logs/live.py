"""``--foxglove [HOST:]PORT``: the recorder's messages served live to Foxglove over its WebSocket
protocol (:mod:`omnibot.logs.foxglove_ws`, both subprotocol names), the same channels and ROS 2
schemas as the log file, so Foxglove shows a running robot as it shows a recorded one; and
Foxglove's Teleop panel as a command source.

Access, as the dashboard's (:mod:`omnibot.web.access`): the ``Host`` must name this server, a
browser's ``Origin`` must be this server or Foxglove's web app, and bound anywhere but loopback
(``--foxglove 0.0.0.0:8765``) an access token is required (the one given with
``--foxglove-token`` or ``$OMNIBOT_FOXGLOVE_TOKEN``, else a random one, printed in the URL:
``ws://HOST:PORT/?token=TOKEN``); a token given on loopback is required there too. The process
listens on that one port and no other.

Client publish: a Foxglove client may advertise ``cmd_vel`` (or ``/cmd_vel``) with a
``geometry_msgs/Twist`` schema (``geometry_msgs/msg/Twist`` too) in ``cdr`` or ``json``, as the
Teleop panel does; each message whose numbers are numbers (JSON numbers, finite; a string, a bool
or null is refused and the client told why) is handed to the :class:`PanelSource`, a source of the
runtime's arbitration (priority 30: under the page's stick, over the follower) that stops the
robot when the panel stops publishing for :data:`PANEL_HOLD` s.
"""

from __future__ import annotations

import json
import logging
import math
import threading
from typing import Any

from omnibot.errors import ConfigError
from omnibot.logs import schemas
from omnibot.logs.foxglove_conn import ClientChannel
from omnibot.logs.foxglove_ws import FOXGLOVE_APP, FoxgloveServer
from omnibot.logs.topics import TELEOP
from omnibot.motion import Twist
from omnibot.runtime import Cycle, Proposal

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


def _number(value: Any, where: str) -> float:
    """A twist's field: a JSON number (not a bool), finite; ValueError naming ``where`` if not."""
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise ValueError(f"{where}: expected a number, got {json.dumps(value)[:40]}")
    try:
        number = float(value)
    except OverflowError:  # an integer beyond every float
        number = math.inf
    if not math.isfinite(number):
        raise ValueError(f"{where}: expected a finite number, got {str(value)[:40]}")
    return number


def _vector(msg: dict[str, Any], name: str) -> tuple[float, float, float]:
    vector = msg.get(name, {})
    if not isinstance(vector, dict):
        raise ValueError(f"{name}: expected an object {{x, y, z}}")
    x, y, z = (_number(vector.get(k, 0.0), f"{name}.{k}") for k in "xyz")
    return x, y, z


def decode_twist(encoding: str, data: bytes) -> Twist:
    """A geometry_msgs/Twist as a client sends it (``cdr`` or ``json``); ValueError, saying what is
    wrong, if it is not one: not JSON or CDR of a Twist, a field that is no number (``"0.3"``,
    ``true``, ``null``) or not finite."""
    if encoding == "json":
        msg = json.loads(data)
        if not isinstance(msg, dict):
            raise ValueError("expected a JSON object {linear, angular}")
        (vx, vy, _), (_, _, w) = _vector(msg, "linear"), _vector(msg, "angular")
    elif encoding == "cdr":
        cdr = schemas.deserialize(data, "geometry_msgs/msg/Twist")
        vx, vy, w = (
            _number(float(value), where)
            for value, where in (
                (cdr.linear.x, "linear.x"),
                (cdr.linear.y, "linear.y"),
                (cdr.angular.z, "angular.z"),
            )
        )
    else:
        raise ValueError(f"encoding {encoding!r} (expected cdr or json)")
    return Twist(vx, vy, w)


class _Panel:
    """What clients publish, for the panel source: twists on :data:`TELEOP`; anything else refused."""

    def __init__(self, panel: PanelSource) -> None:
        self.panel = panel

    def advertised(self, channel: ClientChannel) -> None:
        if channel.topic.lstrip("/") != TELEOP or channel.schema_name not in TWIST_SCHEMAS:
            raise ValueError(f"only {TELEOP} ({' or '.join(sorted(TWIST_SCHEMAS))}) drives the robot")
        if channel.encoding not in ("cdr", "json"):
            raise ValueError(f"encoding {channel.encoding!r} (expected cdr or json)")

    def received(self, channel: ClientChannel, data: bytes) -> None:
        try:
            twist = decode_twist(channel.encoding, data)
        except ValueError:
            raise
        except Exception as exc:  # a CDR decoder's own error: not a Twist
            raise ValueError(f"cannot decode a Twist: {exc}") from None
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
    """A Foxglove WebSocket server on ``host:port`` (0: a free port, see :attr:`port`; the access
    rules of the module docstring, ``origins`` the browser origins allowed besides its own); call it
    as a recorder mirror, ``live(topic, typename, cdr_bytes, ns)``; :attr:`panel` is the Teleop
    panel's source (a runtime adds it); :attr:`url` is where to connect; :meth:`close` stops it."""

    def __init__(
        self,
        port: int = DEFAULT_PORT,
        *,
        host: str = HOST,
        token: str | None = None,
        name: str = "omnibot",
        origins: tuple[str, ...] = FOXGLOVE_APP,
    ) -> None:
        from omnibot.web import access_token

        self.host = host
        self.token = access_token(host, token, key="--foxglove-token")
        self.panel = PanelSource()
        self._server = FoxgloveServer(
            host, port, _Panel(self.panel), token=self.token, name=name, origins=origins
        )
        self.port: int = self._server.port
        self._schemas: dict[str, str] = {}

    @property
    def url(self) -> str:
        """Where a Foxglove client connects (with ``?token=`` when one is required)."""
        host = f"[{self.host}]" if ":" in self.host else self.host
        query = f"?token={self.token}" if self.token else ""
        return f"ws://{host}:{self.port}/{query}"

    def __call__(self, topic: str, typename: str, data: bytes, ns: int) -> None:
        """Publish one recorded message (CDR ``data`` of ``typename``) on ``topic``, its channel
        advertised on first use."""
        schema = self._schemas.get(typename)
        if schema is None:
            schema = self._schemas[typename] = schemas.schema_text(typename)
        self._server.publish(topic, typename, schema, data, ns)

    def close(self) -> None:
        """Close every connection and stop the server."""
        self._server.close()
