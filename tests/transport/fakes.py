"""Stand-ins for the tests: a lockstep echo device and a local TCP echo server."""

from __future__ import annotations

import socket
import threading
from types import TracebackType


class EchoDevice:
    """A LockstepDevice that echoes each complete line ``latency`` s (device time) after it arrived.

    ``per_byte=True`` echoes every byte on the next tick instead (for throughput tests).
    """

    def __init__(self, *, tick: float = 0.001, latency: float = 0.002, per_byte: bool = False) -> None:
        self.tick = tick
        self.time = 0.0
        self._steps = 0
        self.latency = latency
        self.per_byte = per_byte
        self.received = bytearray()
        self.receive_times: list[tuple[float, int]] = []  # (device time, bytes) per receive()
        self._line = bytearray()
        self._pending: list[tuple[float, bytes]] = []  # (due time, line)
        self._out = bytearray()
        self.closed = False

    def receive(self, data: bytes) -> None:
        self.received += data
        self.receive_times.append((self.time, len(data)))
        if self.per_byte:
            self._out += data
            return
        for byte in data:
            self._line.append(byte)
            if byte == 0x0A:
                self._pending.append((self.time + self.latency, bytes(self._line)))
                self._line.clear()

    def step(self) -> None:
        self._steps += 1
        self.time = self._steps * self.tick
        while self._pending and self._pending[0][0] <= self.time + 1e-12:
            self._out += self._pending.pop(0)[1]

    def transmit(self) -> bytes:
        out, self._out = bytes(self._out), bytearray()
        return out

    def close(self) -> None:
        self.closed = True


class QuietEcho(EchoDevice):
    """An :class:`EchoDevice` that takes quiet stretches in one call (a QuietSteps device)."""

    def run_quiet(self, ticks: int) -> int:
        taken = 0
        while taken < ticks and not self._out:
            self.step()
            taken += 1
        return taken


class EchoServer:
    """A TCP echo server on 127.0.0.1 (ephemeral port) serving one client at a time in a thread."""

    def __init__(self) -> None:
        self._listener = socket.create_server(("127.0.0.1", 0))
        self._listener.settimeout(0.05)
        self.port: int = self._listener.getsockname()[1]
        self._stop = threading.Event()
        self._client: socket.socket | None = None
        self._thread = threading.Thread(target=self._serve, name="echo-server", daemon=True)
        self._thread.start()

    def _serve(self) -> None:
        while not self._stop.is_set():
            try:
                conn, _ = self._listener.accept()
            except TimeoutError:
                continue
            self._client = conn
            with conn:
                conn.settimeout(0.05)
                while not self._stop.is_set():
                    try:
                        data = conn.recv(4096)
                    except TimeoutError:
                        continue
                    except OSError:
                        break
                    if not data:
                        break
                    conn.sendall(data)
            self._client = None

    def drop_client(self) -> None:
        """Close the current connection from the server side."""
        client = self._client
        if client is not None:
            client.shutdown(socket.SHUT_RDWR)

    def close(self) -> None:
        self._stop.set()
        self._thread.join(5)
        self._listener.close()

    def __enter__(self) -> EchoServer:
        return self

    def __exit__(
        self, exc_type: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None
    ) -> None:
        self.close()
