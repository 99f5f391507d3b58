"""The client's link: bytes written and read (traced), a failure handled, reopening (docs/client.md).

:class:`Connection` is the object a :class:`~omnibot.client.client.RobotClient` owns for it. A
LinkError from the link is handed to the client (``failed``: it fails the commands waiting and
resets its protocol state), then the link is reopened, retrying ``reconnect`` s (None: not
reopened); while it stays broken the next call tries again first (:meth:`Connection.ensure_open`)
and tells the failure that broke it.
"""

from __future__ import annotations

from collections.abc import Callable

from omnibot.client.tracing import Tracers
from omnibot.errors import LinkError
from omnibot.transport import Clock, Link


class Connection:
    """``link`` and what happened to it: ``reconnect`` s ``link.reopen`` may retry after a LinkError
    (None: do not reopen), ``failed(exc)`` what the client does when the link fails."""

    def __init__(self, link: Link, reconnect: float | None, failed: Callable[[LinkError], None]) -> None:
        self.link = link
        self.reconnect = reconnect
        """Seconds ``link.reopen`` may retry after a LinkError (None: do not reopen)."""
        self.tracers = Tracers(self)
        """Told the link's bytes (and, by the client, the commands and replies): a recorder."""
        self._failed = failed
        self._broken = False
        self._failure: LinkError | None = None  # why the link broke (told again if it stays broken)

    @property
    def clock(self) -> Clock:
        """The link's clock."""
        return self.link.clock

    @property
    def broken(self) -> bool:
        """True after the link failed, until it is open again."""
        return self._broken

    def write(self, data: bytes) -> None:
        """Write ``data`` to the link (a LinkError: handled, then raised)."""
        if self.tracers:
            self.tracers.link_bytes("TX", data)
        try:
            self.link.write(data)
        except LinkError as exc:
            self._fail(exc)
            raise

    def read(self, timeout: float, gather: tuple[bytes, int] | None = None) -> bytes:
        """What the link has within ``timeout`` s (a LinkError: handled, then raised). ``gather``
        (ends, most): the reader acts only on those (:meth:`~omnibot.transport.Link.read_gathered`);
        not while tracing, whose recorder is told every read as it came."""
        try:
            if gather is not None and not self.tracers:
                data = self.link.read_gathered(*gather, 4096, timeout)
            else:
                data = self.link.read(4096, timeout)
        except LinkError as exc:
            self._fail(exc)
            raise
        if data and self.tracers:
            self.tracers.link_bytes("RX", data)
        return data

    def ensure_open(self) -> None:
        """Before a call: LinkError if the link is closed, or broken and not reopened now."""
        if self.link.closed:
            raise LinkError(f"link {self.link.url} is closed")
        if self._broken:
            if self.reconnect is None:
                raise LinkError(f"link {self.link.url} failed and reconnecting is off ({self._failure})")
            try:
                self.link.reopen(retry=self.reconnect)
            except LinkError as exc:  # the failure is the news, not the port missing since
                raise LinkError(f"{self._failure}; reopening it failed: {exc}") from exc
            self._broken = False

    def close(self) -> None:
        """Close the link (idempotent)."""
        if self.tracers and not self.link.closed:
            self.tracers.link_bytes("CLOSE")
        self.link.close()

    def _fail(self, exc: LinkError) -> None:
        self.tracers.link_bytes("ERR", note=str(exc))
        self._failed(exc)
        self._broken = True
        self._failure = exc
        if self.reconnect is not None and not self.link.closed:
            try:
                self.link.reopen(retry=self.reconnect)
                self._broken = False
            except LinkError:
                pass
