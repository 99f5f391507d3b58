"""Who may talk to the dashboard: the Host check (DNS rebinding), the Origin check (cross-site
websockets), the access token and the per-page message rate.

DNS rebinding: a site the user opens (``evil.example``) makes its name resolve to 127.0.0.1, and its
script then talks to the dashboard as "same origin" with ``Host: evil.example:PORT``. A name the
server does not know in ``Host`` is therefore refused, for plain HTTP (403) and for the websocket
(closed with 1008 before it is accepted, which the client sees as 403), as Jupyter's ``check_host``
does. Allowed ``Host`` values, always with the server's port (it may be left out on port 80):

* bound to loopback: ``127.0.0.1``, ``localhost``, ``[::1]`` and the bound address;
* bound to one address: that address (and the name given to ``--host``);
* bound to every address (``0.0.0.0``, ``::``): any IP address literal and ``localhost``;
* in every case the names given with ``--allow-host`` (e.g. ``robot.local``).

An IP literal in ``Host`` cannot come from a rebound name, so it is never the attack.
"""

from __future__ import annotations

import hmac
import ipaddress
import math
import secrets
import socket
import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from urllib.parse import urlsplit

from starlette.types import ASGIApp, Receive, Scope, Send

from omnibot.errors import ConfigError

LOOPBACK_NAMES = ("127.0.0.1", "localhost", "[::1]")
REFUSED_HOST = b"The Host header names a server this dashboard does not serve (DNS rebinding?)."


def _ip(text: str) -> ipaddress.IPv4Address | ipaddress.IPv6Address | None:
    try:
        return ipaddress.ip_address(text.strip("[]"))
    except ValueError:
        return None


def is_loopback(host: str) -> bool:
    """True for 127.0.0.0/8, ::1 and localhost."""
    if host.lower() == "localhost":
        return True
    address = _ip(host)
    return address is not None and address.is_loopback


def _host_key(host: str) -> str:
    """A host as it appears in a ``Host`` header: lower case, IPv6 in brackets, in compressed form."""
    host = host.strip().lower()
    address = _ip(host)
    if address is None:
        return host.rstrip(".")
    return f"[{address.compressed}]" if address.version == 6 else address.compressed


def check_host_name(name: str) -> str:
    """An ``--allow-host`` name, checked (a DNS name or an IP address, no port or scheme)."""
    text = name.strip().lower()
    labels = text.rstrip(".").split(".")
    plain = all(label and len(label) <= 63 and label.replace("-", "").isalnum() for label in labels)
    if _ip(text) is None and not (plain and len(text) <= 253 and text.isascii()):
        raise ConfigError(f"expected a host name such as robot.local, got {name!r}", key="--allow-host")
    return _host_key(text)


@dataclass(frozen=True)
class HostPolicy:
    """Which ``Host`` header values the server answers (see the module docstring)."""

    port: int
    names: frozenset[str]
    any_ip: bool = False

    @classmethod
    def for_bind(cls, host: str, port: int, allow: Iterable[str] = ()) -> HostPolicy:
        """The policy of a server bound to ``host:port`` with the extra names ``allow``."""
        names = {check_host_name(a) for a in allow} | {_host_key(host)}
        address = _ip(host)
        wildcard = address is not None and address.is_unspecified
        if is_loopback(host) or wildcard:
            names |= {_host_key(n) for n in LOOPBACK_NAMES}
        return cls(port, frozenset(names), any_ip=wildcard)

    def allows(self, header: str | None) -> bool:
        """Whether a request with this ``Host`` header is for this server."""
        if not header:
            return False
        try:
            parts = urlsplit(f"//{header}")
            port = parts.port
        except ValueError:  # a port that is not a number, an unclosed bracket
            return False
        name = parts.hostname
        if name is None or (port if port is not None else 80) != self.port:
            return False
        key = _host_key(name)
        return key in self.names or (self.any_ip and _ip(name) is not None)


def same_origin(origin: str | None, host: str | None) -> bool:
    """A websocket's ``Origin`` is this server (a browser on another site may not drive the robot);
    no ``Origin``: not a browser, nothing to protect."""
    if origin is None:
        return True
    return bool(host) and urlsplit(origin).netloc.lower() == (host or "").lower()


TOKEN_MIN = 8
"""Characters an access token given by the user must have at least."""


def access_token(host: str, token: str | None, key: str = "--token") -> str | None:
    """The token a server bound to ``host`` requires: the one given (checked; ``key`` names the option
    in the error), else a fresh random one off loopback, else None (the dashboard, Foxglove live)."""
    if token is not None:
        if len(token) < TOKEN_MIN:
            raise ConfigError(f"an access token needs at least {TOKEN_MIN} characters", key=key)
        return token
    return None if is_loopback(host) else secrets.token_urlsafe(18)


def token_ok(token: str | None, given: str | None) -> bool:
    """``given`` matches the access token (compared in constant time); no token: always."""
    return token is None or (given is not None and hmac.compare_digest(given.encode(), token.encode()))


class HostCheck:
    """ASGI middleware: requests whose ``Host`` the policy refuses get 403 (HTTP) or a websocket
    closed before it is accepted (1008, seen by the client as 403), and never reach the app."""

    def __init__(self, app: ASGIApp, policy: HostPolicy) -> None:
        self.app = app
        self.policy = policy
        self.refused = 0

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        """Pass the request on when the policy allows its single ``Host`` header; refuse it otherwise."""
        if scope["type"] not in ("http", "websocket"):
            await self.app(scope, receive, send)
            return
        hosts = [v.decode("latin-1") for k, v in scope.get("headers", []) if k == b"host"]
        if len(hosts) == 1 and self.policy.allows(hosts[0]):
            await self.app(scope, receive, send)
            return
        self.refused += 1
        if scope["type"] == "websocket":
            await receive()  # websocket.connect
            await send({"type": "websocket.close", "code": 1008, "reason": "Host not allowed"})
            return
        await send(
            {
                "type": "http.response.start",
                "status": 403,
                "headers": [(b"content-type", b"text/plain; charset=utf-8"), (b"cache-control", b"no-store")],
            }
        )
        await send({"type": "http.response.body", "body": REFUSED_HOST})


@dataclass
class RateLimit:
    """A token bucket: ``rate`` messages a second on average, bursts of up to ``burst``."""

    rate: float
    burst: float
    clock: Callable[[], float] = time.monotonic
    _level: float = field(init=False)
    _last: float = field(init=False)

    def __post_init__(self) -> None:
        if not (math.isfinite(self.rate) and self.rate > 0 and self.burst >= 1):
            raise ValueError(f"a rate limit needs rate > 0 and burst >= 1, got {self.rate}, {self.burst}")
        self._level = self.burst
        self._last = self.clock()

    def take(self) -> bool:
        """Count one message; False when it is over the limit."""
        now = self.clock()
        self._level = min(self.burst, self._level + (now - self._last) * self.rate)
        self._last = now
        if self._level < 1.0:
            return False
        self._level -= 1.0
        return True


def listening_socket(host: str, port: int, *, host_key: str, port_key: str, backlog: int) -> socket.socket:
    """A listening TCP socket on ``host:port`` (0: any free port), or a ConfigError saying why not:
    an address that does not resolve (``host_key``) or cannot be listened on (``port_key``)."""
    try:
        infos = socket.getaddrinfo(host, port, type=socket.SOCK_STREAM, flags=socket.AI_PASSIVE)
    except (socket.gaierror, UnicodeError) as exc:
        raise ConfigError(f"cannot resolve {host!r}: {exc}", key=host_key) from None
    family, kind, proto, _, address = infos[0]
    sock = socket.socket(family, kind, proto)
    try:
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        sock.bind(address)
        sock.listen(backlog)
    except OSError as exc:
        sock.close()
        raise ConfigError(f"cannot listen on {host}:{port}: {exc.strerror or exc}", key=port_key) from None
    return sock
