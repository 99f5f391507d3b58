"""TCP client link (``tcp://host:port``): e.g. a serial-to-network bridge or a remote emulator.

The socket stays in blocking mode (so a ``write`` from one thread is never cut short by another
thread's read timeout); reads wait with ``select``. Nagle is off: commands are short and latency
matters. The peer closing the connection, a reset or a refused connect is a
:class:`~omnibot.errors.LinkError`; :meth:`TcpLink.reopen` connects again.
"""

from __future__ import annotations

import contextlib
import select
import socket

from omnibot.errors import LinkError
from omnibot.transport.base import Clock, Link, WallClock

__all__ = ["TcpLink"]


class TcpLink(Link):
    """A :class:`Link` over a TCP connection to ``host:port``."""

    def __init__(
        self,
        host: str,
        port: int,
        *,
        connect_timeout: float = 5.0,
        open_retry: float = 0.0,
        retry_interval: float = 0.1,
        url: str | None = None,
        clock: Clock | None = None,
    ) -> None:
        if not 0 < port < 65536:
            raise ValueError(f"TCP port must be 1..65535, got {port}")
        self.host = host
        self.port = port
        self.connect_timeout = connect_timeout
        self.open_retry = open_retry
        self.retry_interval = retry_interval
        shown = f"[{host}]" if ":" in host else host
        super().__init__(url or f"tcp://{shown}:{port}", clock or WallClock())
        self._sock: socket.socket | None = None
        self._connect(open_retry)

    def reopen(self, retry: float | None = None) -> None:
        """Drop the connection if any and connect again, retrying for ``retry`` s."""
        self._check_open()
        self._release()
        self._connect(self.open_retry if retry is None else retry)

    def _connect(self, retry: float) -> None:
        deadline = self.clock.now() + max(0.0, retry)
        while True:
            try:
                sock = socket.create_connection((self.host, self.port), timeout=self.connect_timeout)
            except OSError as exc:
                if self.clock.now() >= deadline:
                    raise LinkError(f"cannot connect to {self.host}:{self.port}: {exc}") from exc
                self.clock.sleep(self.retry_interval)
                continue
            sock.settimeout(None)
            sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            self._sock = sock
            return

    def _socket(self) -> socket.socket:
        if self._sock is None:
            raise LinkError(f"{self.url} is not connected (call reopen())")
        return self._sock

    def _broken(self, why: str) -> LinkError:
        self._release()
        return LinkError(f"{self.url}: {why}")

    def _release(self) -> None:
        sock, self._sock = self._sock, None
        if sock is not None:
            with contextlib.suppress(OSError):
                sock.shutdown(socket.SHUT_RDWR)
            sock.close()

    def _write(self, data: bytes) -> None:
        sock = self._socket()
        try:
            sock.sendall(data)
        except OSError as exc:
            raise self._broken(f"send failed: {exc}") from exc

    def _read(self, max_bytes: int, timeout: float | None) -> bytes:
        sock = self._socket()
        try:
            ready, _, _ = select.select([sock], [], [], timeout)
            if not ready:
                return b""
            data = sock.recv(max_bytes)
        except OSError as exc:
            raise self._broken(f"receive failed: {exc}") from exc
        if not data:
            raise self._broken("connection closed by peer")
        return data

    def _close(self) -> None:
        self._release()
