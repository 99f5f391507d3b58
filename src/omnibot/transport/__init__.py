"""Byte links chosen by URL: serial ports, TCP, the in-process lockstep simulator, and wrappers.

``open_link(url)`` (grammar in :mod:`omnibot.transport.url`) returns a :class:`Link`: ``write``,
``read(max_bytes, timeout)`` (``b""`` on timeout), ``close``, ``url``, ``closed`` and ``clock`` (wall or
simulated time). Links move bytes only; they know nothing of the protocol or of the simulator.

Modules: ``base`` (Link, Clock), ``url`` (grammar, open_link, register_scheme), ``linkurl`` (LinkUrl:
a layer's options), ``serial_link``, ``tcp``, ``lockstep`` (LockstepDevice, LockstepLink), ``device`` (find_device, find_simulator: the
simulator behind a link, if any), ``spy`` (trace), ``faults`` (fault injection),
``pacing`` (baud-rate token bucket), ``pty_bridge`` (serve a device on a pty; POSIX only, import it
directly).
"""

from omnibot.transport.base import Clock, Link, WallClock
from omnibot.transport.device import find_device, find_simulator
from omnibot.transport.faults import FaultLink, FaultStats
from omnibot.transport.linkurl import LinkUrl
from omnibot.transport.lockstep import DEFAULT_BAUD, LockstepClock, LockstepDevice, LockstepLink
from omnibot.transport.pacing import Pacer
from omnibot.transport.serial_link import SerialLink
from omnibot.transport.spy import SpyEvent, SpyLink, format_event
from omnibot.transport.tcp import TcpLink
from omnibot.transport.url import (
    open_link,
    parse_link_url,
    register_scheme,
    registered_schemes,
    unregister_scheme,
)

__all__ = [
    "DEFAULT_BAUD",
    "Clock",
    "FaultLink",
    "FaultStats",
    "Link",
    "LinkUrl",
    "LockstepClock",
    "LockstepDevice",
    "LockstepLink",
    "Pacer",
    "SerialLink",
    "SpyEvent",
    "SpyLink",
    "TcpLink",
    "WallClock",
    "base",
    "device",
    "find_device",
    "find_simulator",
    "format_event",
    "lockstep",
    "open_link",
    "parse_link_url",
    "pty_bridge",
    "register_scheme",
    "registered_schemes",
    "serial_link",
    "spy",
    "unregister_scheme",
    "url",
]
