"""What a recorder hears from a client: the :class:`Tracer` protocol and a client's :class:`Tracers`.

A tracer (:meth:`~omnibot.client.client.RobotClient.add_tracer`; ``--log``'s recorder is one) is
handed every byte on the link as the ``spy+`` wrapper sees it, and every command sent and reply
matched, decoded; events go to listeners instead (:class:`~omnibot.client.events.Listeners`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Protocol

from omnibot.client.events import log
from omnibot.protocol.messages import Malformed, Message

if TYPE_CHECKING:
    from omnibot.transport import Clock


class Tracer(Protocol):
    """What a recorder hears from the client (:meth:`RobotClient.add_tracer`): every byte on the link
    as the ``spy+`` wrapper sees it, and every command sent and reply matched, decoded (events go to
    listeners). Times are the link clock's."""

    def link_bytes(self, t: float, kind: str, data: bytes = b"", note: str = "") -> None:
        """``TX`` written, ``RX`` read, ``ERR`` the link failed (``note``), ``CLOSE``."""

    def message(self, t: float, direction: str, message: Message | Malformed) -> None:
        """``command`` sent or ``reply`` matched."""


class Host(Protocol):
    """What the tracers ask of the client that owns them: its link's clock, read as each is told."""

    @property
    def clock(self) -> Clock:
        """The link's clock."""


class Tracers:
    """The tracers of ``host`` (a client), each told in turn at the time of its link's clock; one that
    raises is logged once and dropped (a recorder that fails on every byte would otherwise log a
    traceback per byte), and the others still hear. False while there is none (nothing to encode)."""

    def __init__(self, host: Host) -> None:
        self._host = host
        self._tracers: list[Tracer] = []

    def add(self, tracer: Tracer) -> None:
        """Hand ``tracer`` everything from now on."""
        self._tracers.append(tracer)

    def remove(self, tracer: Tracer) -> None:
        """Stop handing ``tracer`` anything (no error if it was not there)."""
        self._tracers = [t for t in self._tracers if t is not tracer]

    def __bool__(self) -> bool:
        return bool(self._tracers)

    def link_bytes(self, kind: str, data: bytes = b"", note: str = "") -> None:
        """Bytes on the link: ``TX``, ``RX``, ``ERR`` (``note`` says why), ``CLOSE``."""
        for tracer in self._tracers:
            try:
                tracer.link_bytes(self._host.clock.now(), kind, data, note)
            except Exception:
                self._drop(tracer)

    def message(self, direction: str, message: Message | Malformed) -> None:
        """A ``command`` sent or a ``reply`` matched."""
        for tracer in self._tracers:
            try:
                tracer.message(self._host.clock.now(), direction, message)
            except Exception:
                self._drop(tracer)

    def _drop(self, tracer: Tracer) -> None:
        """``tracer`` raised (the exception being handled): log it and hand it nothing more."""
        log.exception("tracer %r failed; it is removed (the link goes on)", tracer)
        self.remove(tracer)
