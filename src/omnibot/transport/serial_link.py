"""Serial ports through pyserial: a real UART, a pty, or a pyserial URL such as ``loop://``.

8N1 at ``baud`` (default 115200). Every pyserial or OS error becomes
:class:`~omnibot.errors.LinkError`, and the link is then *broken*: the port is released and reads and
writes raise LinkError until :meth:`SerialLink.reopen` succeeds (``open_retry`` seconds of retrying let
a client ride out a USB adapter being re-plugged or an emulator restarting).
"""

from __future__ import annotations

import contextlib

import serial

from omnibot.errors import ConfigError, LinkError
from omnibot.transport.base import Clock, Link, WallClock

__all__ = ["SerialLink"]


class SerialLink(Link):
    """A :class:`Link` on a serial port; ``port`` is a device path or a pyserial URL."""

    def __init__(
        self,
        port: str,
        *,
        baud: int = 115200,
        open_retry: float = 0.0,
        retry_interval: float = 0.1,
        url: str | None = None,
        clock: Clock | None = None,
    ) -> None:
        if baud <= 0:
            raise ConfigError(f"must be a positive integer, got {baud}", key="baud")
        self.port = port
        self.baud = baud
        self.open_retry = open_retry
        self.retry_interval = retry_interval
        super().__init__(url or f"serial://{port}?baud={baud}", clock or WallClock())
        self._serial: serial.Serial | None = None
        self._failure: str | None = None
        """Why the port broke (None: it did not, or it was reopened since)."""
        self._open(open_retry)

    @property
    def is_open(self) -> bool:
        """True while the port is open (False once broken or closed)."""
        return self._serial is not None

    def reopen(self, retry: float | None = None) -> None:
        """Close the port if open and open it again, retrying for ``retry`` s (default: open_retry)."""
        self._check_open()
        self._release()
        self._open(self.open_retry if retry is None else retry)

    # -- internals -----------------------------------------------------------------------------

    def _open_once(self) -> serial.Serial:
        if "://" in self.port:
            return serial.serial_for_url(self.port, baudrate=self.baud, timeout=0)
        return serial.Serial(self.port, baudrate=self.baud, timeout=0, exclusive=True)

    def _open(self, retry: float) -> None:
        deadline = self.clock.now() + max(0.0, retry)
        while True:
            try:
                self._serial = self._open_once()
                self._failure = None
                return
            except ValueError as exc:  # bad settings: retrying will not help
                raise ConfigError(f"cannot open serial port {self.port}: {exc}") from exc
            except (serial.SerialException, OSError) as exc:
                if self.clock.now() >= deadline:
                    raise LinkError(f"cannot open serial port {self.port}: {exc}") from exc
            self.clock.sleep(self.retry_interval)

    def _port(self) -> serial.Serial:
        if self._serial is None:
            # a broken port says why it broke in every thread that uses it next (the reader's error
            # and the writer's then read alike, whichever a front end reports)
            raise LinkError(self._failure or f"serial port {self.port} is not open (call reopen())")
        return self._serial

    def _broken(self, exc: Exception) -> LinkError:
        self._failure = f"serial port {self.port} failed: {exc}"
        self._release()
        return LinkError(self._failure)

    def _release(self) -> None:
        ser, self._serial = self._serial, None
        if ser is not None:
            with contextlib.suppress(serial.SerialException, OSError):
                ser.close()

    def _write(self, data: bytes) -> None:
        ser = self._port()
        try:
            ser.write(data)
        except (serial.SerialException, OSError) as exc:
            raise self._broken(exc) from exc

    def _read(self, max_bytes: int, timeout: float | None) -> bytes:
        ser = self._port()
        try:
            if ser.timeout != timeout:
                ser.timeout = timeout
            waiting = ser.in_waiting
            if waiting:
                return bytes(ser.read(min(waiting, max_bytes)))
            data = bytes(ser.read(1))
            if data and max_bytes > 1:
                more = ser.in_waiting
                if more:
                    data += ser.read(min(more, max_bytes - 1))
            return data
        except (serial.SerialException, OSError) as exc:
            raise self._broken(exc) from exc

    def _close(self) -> None:
        ser = self._serial
        if ser is not None and hasattr(ser, "cancel_read"):
            with contextlib.suppress(serial.SerialException, OSError):
                ser.cancel_read()  # wake a reader blocked in another thread
        self._release()
