"""Link URLs: one string picks the transport. ``open_link(url)`` parses it and opens the link.

Grammar::

    url     := { wrapper "+" } base [ "?" option { "&" option } ]
    option  := [ layer "." ] name [ "=" value ]
    wrapper := "spy" | "faults"

    base (scheme "serial", the default):
      /dev/ttyUSB0                        a serial device path (anything without "://")
      serial:///dev/ttyUSB0               the same, explicit
          baud=115200   line speed, 8N1 (default 115200)
          retry=0       seconds to keep retrying to open (0: fail at once)
      loop:// socket://H:P rfc2217://H:P hwgrep://RE alt://PORT
                                          pyserial URLs, opened by pyserial (options as above
                                          plus the handler's own: logging, timeout, n, class, ...)
    base (scheme "tcp"):
      tcp://host:port                     a TCP connection ([::1]:port for IPv6)
          connect_timeout=5   seconds per connect attempt
          retry=0             seconds to keep retrying to connect
    base (scheme "sim", registered by omnibot.sim.scheme; see register_scheme):
      sim://PRESET                        in-process lockstep simulator, simulated time
          seed=N surface=NAME world=NAME baud=115200 (0 = unpaced)
          pose=X,Y,THETA      start pose, m, m, degrees (default: the world's start)
          fleet=NAME          one robot of a fleet: the links of one process with the same
                              fleet share one world and one simulated clock (omnibot.sim.fleet_link)
          name=R              the robot's name in its fleet (default r1, r2, ...)
    wrappers:
      spy+<url>       trace every read and write (hexdump, timestamps on the link's clock)
          file=PATH     write the trace to PATH (default: stderr)
          all           also trace reads that timed out empty
      faults+<url>    inject faults, reproducibly
          drop=P corrupt=P   per-byte probabilities (default 0)
          delay_ms=MS jitter_ms=MS   hold bytes MS (+ uniform 0..jitter) ms (default 0)
          seed=N             random seed (default 0)
          dir=both|tx|rx     which direction to disturb (default both)

Examples: ``/dev/ttyACM0``, ``serial:///dev/ttyUSB0?baud=57600&retry=5``, ``tcp://192.168.1.7:4000``,
``sim://omni4?seed=3``, ``sim://omni3?fleet=lab&name=r2&pose=2,1,90``, ``spy+sim://omni4?file=trace.txt``,
``faults+tcp://localhost:4000?drop=0.01&corrupt=0.01&delay_ms=5&seed=1``.

Options: all options sit in the one query at the end. An option belongs to the innermost layer that
has an option of that name; ``layer.name=value`` sends it to a given layer. So in
``faults+sim://omni4?seed=3&drop=0.1`` the seed is the simulator's; ``faults.seed=3`` would be the
fault injector's. A bad URL raises :class:`~omnibot.errors.ConfigError` (a ValueError) naming the bad
part and listing what is valid; a link that cannot be opened raises LinkError.

Registering a scheme: ``register_scheme("sim", factory, options=("seed", ...))`` where
``factory(u: LinkUrl) -> Link`` reads ``u.target`` and ``u.get_int(...)``-style options and passes
``url=u.url`` to the link it makes. The ``sim`` scheme is imported on first use from the module named in
:data:`SCHEME_PROVIDERS`, which registers it when imported.
"""

from __future__ import annotations

import difflib
import importlib
import re
import sys
import threading
import urllib.parse
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import cast

from omnibot.errors import ConfigError, LinkError
from omnibot.transport.base import Link
from omnibot.transport.linkurl import LinkUrl

__all__ = [
    "SCHEME_PROVIDERS",
    "SchemeInfo",
    "open_link",
    "parse_link_url",
    "register_scheme",
    "registered_schemes",
    "unregister_scheme",
]

SCHEME_PROVIDERS: dict[str, str] = {"sim": "omnibot.sim.scheme", "uno": "omnibot.uno.hil"}
"""Scheme -> module that registers it when imported (imported on first use of the scheme)."""

_PYSERIAL_OPTIONS: dict[str, tuple[str, ...]] = {
    "loop": ("logging",),
    "socket": ("logging",),
    "rfc2217": ("logging", "ign_set_control", "poll_modem", "timeout"),
    "hwgrep": ("n", "skip_busy"),
    "alt": ("class",),
}
_SERIAL_OPTIONS = ("baud", "retry")


Factory = Callable[[LinkUrl], Link]
Wrap = Callable[[Link, LinkUrl], Link]


@dataclass(frozen=True)
class SchemeInfo:
    """A registered base scheme: its factory and the option names it accepts."""

    name: str
    factory: Factory
    options: tuple[str, ...] = ()
    help: str = ""


_registry: dict[str, SchemeInfo] = {}
_registry_lock = threading.Lock()


def register_scheme(name: str, factory: Factory, *, options: Iterable[str] = (), help: str = "") -> None:
    """Make ``name://...`` URLs open with ``factory(LinkUrl)``; ``options`` are the accepted names.

    Registering a name again replaces the earlier factory (so a reloaded module re-registers).
    """
    key = name.lower()
    if not re.fullmatch(r"[a-z][a-z0-9_-]*", key) or key in _WRAPPERS:
        raise ValueError(f"invalid scheme name {name!r}")
    with _registry_lock:
        _registry[key] = SchemeInfo(key, factory, tuple(options), help)


def unregister_scheme(name: str) -> None:
    """Forget a registered scheme (no error if it was not registered)."""
    with _registry_lock:
        _registry.pop(name.lower(), None)


def registered_schemes() -> dict[str, SchemeInfo]:
    """The base schemes registered so far (built-in ones included)."""
    with _registry_lock:
        return dict(_registry)


# -- parsing ---------------------------------------------------------------------------------------


def _suggest(word: str, choices: Iterable[str]) -> str:
    close = difflib.get_close_matches(word, list(choices), n=1)
    return f" (did you mean {close[0]!r}?)" if close else ""


def _scheme_info(scheme: str, url: str) -> SchemeInfo:
    info = registered_schemes().get(scheme)
    if info is None and scheme in SCHEME_PROVIDERS:
        module = SCHEME_PROVIDERS[scheme]
        try:
            importlib.import_module(module)
        except ModuleNotFoundError as exc:
            if exc.name is None or not module.startswith(exc.name):
                raise
            raise LinkError(f"{scheme}:// links are not available: module {module} is missing") from exc
        info = registered_schemes().get(scheme)
        if info is None:
            raise LinkError(f"{scheme}:// links are not available: {module} did not register them")
    if info is None:
        valid = sorted({*registered_schemes(), *SCHEME_PROVIDERS})
        raise ConfigError(
            f"unknown link scheme {scheme!r}{_suggest(scheme, valid)} in URL {url!r}; "
            f"valid schemes: {', '.join(valid)}; wrappers: {', '.join(w + '+' for w in _WRAPPERS)}; "
            "or a serial device path like /dev/ttyUSB0",
            key="url",
        )
    return info


def parse_link_url(url: str) -> list[LinkUrl]:
    """Split ``url`` into layers, outermost wrapper first, base last; assign options to layers."""
    if not isinstance(url, str) or not url.strip():
        raise ConfigError(f"a link URL must be a non-empty string, got {url!r}", key="url")
    rest = url.strip()
    wrappers: list[str] = []
    while m := re.match(r"([A-Za-z][A-Za-z0-9_-]*)\+(.*)", rest, re.S):
        name = m[1].lower()
        if name not in _WRAPPERS:
            if "://" in m[2] or m[2].startswith("/"):
                raise ConfigError(
                    f"unknown wrapper {m[1]!r}{_suggest(name, _WRAPPERS)} in URL {url!r}; "
                    f"valid wrappers: {', '.join(w + '+' for w in _WRAPPERS)}",
                    key="url",
                )
            break
        wrappers.append(name)
        rest = m[2]
    body, _, query = rest.partition("?")
    if "://" in body:
        scheme, _, target = body.partition("://")
        scheme = scheme.lower()
    else:
        scheme, target = "serial", body
    info = _scheme_info(scheme, url)
    if scheme == "serial" and not target:
        raise ConfigError(f"no serial device path in URL {url!r} (e.g. serial:///dev/ttyUSB0)", key="url")
    layer_options: list[tuple[str, tuple[str, ...]]] = [(w, _WRAPPERS[w].options) for w in wrappers]
    layer_options.append((scheme, info.options))
    assigned = _assign_options(url, query, layer_options)
    layers = [
        LinkUrl(name, target if i == len(layer_options) - 1 else "", assigned[i], url)
        for i, (name, _) in enumerate(layer_options)
    ]
    outer = layers[0]
    layers[0] = LinkUrl(outer.scheme, outer.target, outer.options, url, url)
    if len(layers) > 1:
        base = layers[-1]
        layers[-1] = LinkUrl(base.scheme, base.target, base.options, url, base.text)
    return layers


def _assign_options(url: str, query: str, layers: list[tuple[str, tuple[str, ...]]]) -> list[dict[str, str]]:
    pairs: list[tuple[str, str]] = []
    for piece in query.split("&") if query else []:
        key, _, value = piece.partition("=")
        if not key:
            raise ConfigError(f"malformed query {query!r} in URL {url!r} (expected a=1&b=2&flag)", key="url")
        pairs.append((urllib.parse.unquote(key), urllib.parse.unquote(value)))
    assigned: list[dict[str, str]] = [{} for _ in layers]
    names = [name for name, _ in layers]
    for key, value in pairs:
        layer_name, dot, option = key.rpartition(".")
        if dot:
            if layer_name not in names:
                raise ConfigError(
                    f"option {key!r} names layer {layer_name!r}, which is not in URL {url!r}; "
                    f"layers: {', '.join(names)}",
                    key=key,
                )
            index = len(names) - 1 - names[::-1].index(layer_name)
            if option not in layers[index][1]:
                raise _unknown_option(url, option, [layers[index]])
        else:
            found = [i for i, (_, accepted) in enumerate(layers) if key in accepted]
            if not found:
                raise _unknown_option(url, key, layers)
            index, option = found[-1], key
        if option in assigned[index]:
            raise ConfigError(f"option given twice in URL {url!r}", key=key)
        assigned[index][option] = value
    return assigned


def _unknown_option(url: str, name: str, layers: list[tuple[str, tuple[str, ...]]]) -> ConfigError:
    valid = [opt for _, accepted in layers for opt in accepted]
    listing = "; ".join(f"{layer}: {', '.join(accepted) or '(none)'}" for layer, accepted in layers)
    return ConfigError(
        f"unknown option{_suggest(name, valid)} in URL {url!r}; valid options: {listing}", key=name
    )


# -- opening ---------------------------------------------------------------------------------------


def open_link(url: str) -> Link:
    """Open the link ``url`` names (see the module docstring for the grammar)."""
    layers = parse_link_url(url)
    base = layers[-1]
    factory = _scheme_info(base.scheme, url).factory
    wraps = [_WRAPPERS[layer.scheme].prepare(layer) for layer in reversed(layers[:-1])]  # check first
    link = factory(base)
    for wrap in wraps:
        try:
            link = wrap(link)
        except BaseException:
            link.close()
            raise
    return link


def _open_serial(u: LinkUrl) -> Link:
    from omnibot.transport.serial_link import SerialLink

    baud = u.get_int("baud", 115200, minimum=1)
    retry = u.get_float("retry", 0.0)
    if u.scheme == "serial":
        return SerialLink(u.target, baud=baud, open_retry=retry, url=u.url)
    own = {k: v for k, v in u.options.items() if k not in _SERIAL_OPTIONS}
    query = urllib.parse.urlencode(own)
    port = f"{u.scheme}://{u.target}" + (f"?{query}" if query else "")
    return SerialLink(port, baud=baud, open_retry=retry, url=u.url)


def _open_tcp(u: LinkUrl) -> Link:
    from omnibot.transport.tcp import TcpLink

    try:
        parts = urllib.parse.urlsplit(f"tcp://{u.target}")
        host, port = parts.hostname, parts.port
    except ValueError as exc:
        raise ConfigError(f"bad host:port {u.target!r} in URL {u.source!r}: {exc}", key="url") from None
    if not host or port is None or parts.path:
        raise ConfigError(f"expected tcp://host:port, got {u.source!r}", key="url")
    return TcpLink(
        host,
        port,
        connect_timeout=u.get_float("connect_timeout", 5.0),
        open_retry=u.get_float("retry", 0.0),
        url=u.url,
    )


# -- wrappers --------------------------------------------------------------------------------------


@dataclass(frozen=True)
class _Wrapper:
    options: tuple[str, ...]
    prepare: Callable[[LinkUrl], Callable[[Link], Link]]
    """Check the layer's options, return the function that wraps the inner link."""


def _prepare_spy(u: LinkUrl) -> Callable[[Link], Link]:
    from omnibot.transport.spy import SpyLink

    path = u.get_str("file", "-")
    all_reads = u.get_bool("all")

    def wrap(inner: Link) -> Link:
        if path == "-":
            return SpyLink(inner, sys.stderr, all_reads=all_reads, url=u.url or None)
        try:
            stream = open(path, "w", encoding="utf-8")  # noqa: SIM115 - the SpyLink owns it
        except OSError as exc:
            raise ConfigError(f"cannot open trace file: {exc}", key="file") from exc
        return SpyLink(inner, stream, all_reads=all_reads, owns_sink=True, url=u.url or None)

    return wrap


def _prepare_faults(u: LinkUrl) -> Callable[[Link], Link]:
    from omnibot.transport.faults import Direction, FaultLink

    direction = u.get_str("dir", "both")
    if direction not in ("both", "tx", "rx"):
        raise ConfigError(f"expected both, tx or rx, got {direction!r} in URL {u.source!r}", key="dir")
    settings = {
        "drop": u.get_float("drop", 0.0, maximum=1.0),
        "corrupt": u.get_float("corrupt", 0.0, maximum=1.0),
        "delay": u.get_float("delay_ms", 0.0) / 1000.0,
        "jitter": u.get_float("jitter_ms", 0.0) / 1000.0,
    }
    seed = u.get_int("seed", 0)

    def wrap(inner: Link) -> Link:
        return FaultLink(
            inner, **settings, seed=seed, direction=cast(Direction, direction), url=u.url or None
        )

    return wrap


_WRAPPERS: dict[str, _Wrapper] = {
    "spy": _Wrapper(("file", "all"), _prepare_spy),
    "faults": _Wrapper(("drop", "corrupt", "delay_ms", "jitter_ms", "seed", "dir"), _prepare_faults),
}

register_scheme("serial", _open_serial, options=_SERIAL_OPTIONS, help="serial device path")
for _name, _extra in _PYSERIAL_OPTIONS.items():
    register_scheme(_name, _open_serial, options=_SERIAL_OPTIONS + _extra, help="pyserial URL")
register_scheme("tcp", _open_tcp, options=("connect_timeout", "retry"), help="tcp://host:port")
