"""Serve a stepped device on a pseudo-terminal in real time (the plumbing of ``omnibot sim --pty``).

::

    host program --(slave: /dev/pts/N)--> kernel pty --(master fd)--> PtyBridge --> device.receive()
                 <--                                  <-- paced  <--           <-- device.transmit()

The bridge owns the master side. The device (any :class:`~omnibot.transport.lockstep.LockstepDevice`)
is stepped once per ``device.tick`` of wall-clock time: the loop wakes every ``period`` (4 ms,
SERVICE_PERIOD) and steps every tick due by then; a late loop catches up the same way, and beyond
``max_catch_up`` seconds behind it skips ticks (counted in ``skipped_ticks``) instead of racing.
Bytes are paced to ``baud`` in both directions (a pty itself does not pace), with a
:class:`~omnibot.transport.pacing.Pacer` per direction that runs on the device's time: every tick
stepped passes the bytes the line carries in one tick, so a loop that wakes late (a starved process)
catches up the line with the device instead of losing all but one burst of it. The long-run rate
stays at most the baud rate, since the device's time never runs ahead of the wall clock.

The host may open, close and reopen the slave at will: while no one has it open the master reports a
hang-up (reads give EIO); the bridge keeps the device running, discards what the device sends (a UART
with nothing attached), flushes stale bytes, and carries on when the slave is opened again
(calling ``on_connect``, if given, each time a host opens it).
"""

from __future__ import annotations

import errno
import math
import os
import select
import termios
import threading
import time
import tty
from collections.abc import Callable, Sequence
from types import TracebackType
from typing import Self

from omnibot import collector
from omnibot.errors import LinkError
from omnibot.transport.lockstep import DEFAULT_BAUD, LockstepDevice
from omnibot.transport.pacing import Pacer

__all__ = ["PtyBridge", "serve_together"]

_READ_CHUNK = 4096

SERVICE_PERIOD = 0.004
"""s of wall clock between the loop's passes. Each pass reads what the host wrote, steps every tick
due (each with its paced bytes) and writes what the line carried, so the device's time and the line
keep real time whatever the period; the period only sets how often the process wakes and so what
it costs. Waking every 1 ms tick cost about 8 % of a core in syscalls and wake-ups alone (the steps
themselves about 0.7 %), enough for a busy machine's scheduler to leave the emulator behind; a
period of a few ms is what a USB serial adapter's latency timer gives a real host anyway."""


class PtyBridge:
    """A pty pair whose master end is served by ``device`` in real time.

    Use as a context manager (``with PtyBridge(dev) as bridge: open(bridge.path)``), or call
    :meth:`start`/:meth:`stop`, or run the loop in the calling thread with :meth:`run` until an Event
    is set and then :meth:`close`. The bridge does not close the device.
    """

    def __init__(
        self,
        device: LockstepDevice,
        *,
        baud: int = DEFAULT_BAUD,
        burst: int = 16,
        max_catch_up: float = 0.1,
        period: float = SERVICE_PERIOD,
        on_connect: Callable[[], None] | None = None,
    ) -> None:
        if device.tick <= 0:
            raise ValueError(f"device tick must be > 0 s, got {device.tick}")
        if period < 0:
            raise ValueError(f"service period must be >= 0 s, got {period}")
        self.device = device
        self.baud = baud
        self.burst = burst
        self.max_catch_up = max_catch_up
        self.period = period
        """Wall-clock seconds between the loop's passes (at least one tick): see SERVICE_PERIOD."""
        self.on_connect = on_connect
        """Called in the bridge's thread each time a host opens the slave (e.g. to reset the device
        the way opening an Arduino's port pulses DTR)."""
        master, slave = os.openpty()
        try:
            tty.setraw(slave)
            self.path: str = os.ttyname(slave)
            """The slave device path for the host to open (e.g. ``/dev/pts/7``)."""
        except BaseException:
            os.close(master)
            raise
        finally:
            os.close(slave)  # the host opens it by path; while nobody has it open we see hang-ups
        os.set_blocking(master, False)
        self._master: int | None = master
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self.error: BaseException | None = None
        """What ended the loop abnormally, if anything (also raised as LinkError by stop())."""
        self.connected = False
        """Whether a host had the slave open at the last look."""
        self.steps = 0
        self.skipped_ticks = 0
        self.bytes_to_device = 0
        self.bytes_to_host = 0
        self.bytes_discarded = 0
        self._begin(time.monotonic())

    # -- lifecycle -----------------------------------------------------------------------------

    def start(self) -> Self:
        """Run the loop in a background thread."""
        if self._master is None:
            raise LinkError("pty bridge is closed")
        if self._thread is not None:
            raise RuntimeError("pty bridge already started")
        self._thread = threading.Thread(
            target=self._thread_main, name=f"omnibot-pty {self.path}", daemon=True
        )
        self._thread.start()
        return self

    def stop(self, timeout: float = 5.0) -> None:
        """Stop the loop, join its thread, close the pty; raise LinkError if the loop had failed."""
        self._stop.set()
        thread, self._thread = self._thread, None
        if thread is not None:
            thread.join(timeout)
            if thread.is_alive():
                raise LinkError(f"pty bridge thread did not stop within {timeout} s")
        self._close_fd()
        if self.error is not None:
            error, self.error = self.error, None
            raise LinkError(f"pty bridge on {self.path} failed: {error}") from error

    close = stop

    def __enter__(self) -> Self:
        return self.start()

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.stop()

    def _thread_main(self) -> None:
        try:
            self.run()
        except BaseException as exc:
            self.error = exc

    def _close_fd(self) -> None:
        master, self._master = self._master, None
        if master is not None:
            os.close(master)

    # -- the loop ------------------------------------------------------------------------------

    def run(self, stop: threading.Event | None = None) -> None:
        """Serve the device until ``stop`` (or :meth:`stop`) is set. Call :meth:`close` afterwards."""
        serve_together([self], self.device.step, stop)

    def _begin(self, now: float) -> None:
        """Start the device's clock and the line at wall-clock time ``now``."""
        self._line_time = now
        self._next_tick = now + self.device.tick
        self._to_device = bytearray()  # read from the host, not yet on the line
        self._to_host = bytearray()  # sent by the device, not yet on the line
        self._wire = bytearray()  # on the line to the host, not yet written to the pty
        # enough burst for one tick's bytes, or a long tick would carry less than the line
        burst = max(self.burst, math.ceil(self.device.tick * self.baud / 10)) if self.baud else self.burst
        self._pace_in = Pacer(self.baud, burst=burst, clock=self._line_clock)
        self._pace_out = Pacer(self.baud, burst=burst, clock=self._line_clock)

    def _line_clock(self) -> float:
        return self._line_time

    def _advance(self, now: float) -> None:
        """Step the device through every tick due at wall-clock time ``now``, each with its bytes."""
        _advance_together([self], self.device.step, now)

    def _before_tick(self) -> None:
        """The line's bytes of one tick reach the device (paced)."""
        self._line_time = self._next_tick
        n = self._pace_in.take(len(self._to_device))
        if n:
            self.device.receive(bytes(self._to_device[:n]))
            del self._to_device[:n]
            self.bytes_to_device += n

    def _after_tick(self) -> None:
        """What the device sent in one tick goes on the line (paced); the next tick is due."""
        self.steps += 1
        out = self.device.transmit()
        if out:
            if self.connected:
                self._to_host += out
            else:
                self.bytes_discarded += len(out)
        n = self._pace_out.take(len(self._to_host))
        if n:
            self._wire += self._to_host[:n]
            del self._to_host[:n]
        self._next_tick += self.device.tick

    def _poll(self, master: int, poller: select.poll) -> None:
        events = 0
        for _, ev in poller.poll(0):
            events |= ev
        hung_up = bool(events & select.POLLHUP) and not events & select.POLLIN
        if hung_up:
            if self.connected:  # the host closed the slave: drop what is in flight
                self.connected = False
                self.bytes_discarded += len(self._to_host) + len(self._wire)
                self._to_host.clear()
                self._wire.clear()
                termios.tcflush(master, termios.TCIOFLUSH)
            return
        if not self.connected:
            self.connected = True
            if self.on_connect is not None:
                self.on_connect()
        if events & select.POLLIN and len(self._to_device) < _READ_CHUNK:
            try:
                data = os.read(master, _READ_CHUNK)
            except BlockingIOError:
                return
            except OSError as exc:
                if exc.errno == errno.EIO:  # slave closed between poll and read
                    self.connected = False
                    return
                raise
            self._to_device += data

    def _send(self, master: int) -> None:
        """Write what the line has carried to the host (already paced)."""
        try:
            written = os.write(master, self._wire)
        except BlockingIOError:
            written = 0
        except OSError as exc:
            if exc.errno == errno.EIO:
                self.connected = False
                return
            raise
        del self._wire[:written]
        self.bytes_to_host += written


def serve_together(
    bridges: Sequence[PtyBridge], step: Callable[[], None], stop: threading.Event | None = None
) -> None:
    """Serve several bridges from one real-time loop, their devices stepped together by ``step()``
    once per tick (a fleet of simulated robots on one clock: ``omnibot sim --pty`` with several
    robots), until ``stop`` or any bridge's own stop is set. Their devices share one tick. The
    command's start is over: the garbage collector released (:func:`omnibot.collector.release`)."""
    collector.release()
    masters = [b._master for b in bridges if b._master is not None]
    if not bridges or len(masters) != len(bridges):
        raise LinkError("pty bridge is closed")
    lead = bridges[0]
    if any(b.device.tick != lead.device.tick for b in bridges):
        raise ValueError("the devices served together must share one tick")
    start = time.monotonic()
    pollers = []
    for bridge, master in zip(bridges, masters, strict=True):
        bridge._begin(start)
        poller = select.poll()
        poller.register(master, select.POLLIN)
        pollers.append(poller)

    def stopped() -> bool:
        return (stop is not None and stop.is_set()) or any(b._stop.is_set() for b in bridges)

    while not stopped():
        for bridge, master, poller in zip(bridges, masters, pollers, strict=True):
            bridge._poll(master, poller)
        now = time.monotonic()
        _advance_together(bridges, step, now)
        for bridge, master in zip(bridges, masters, strict=True):
            if bridge._wire and bridge.connected:
                bridge._send(master)
        wait = next_wake(now, lead._next_tick, lead.period) - time.monotonic()
        if wait > 0:
            time.sleep(wait)


def next_wake(now: float, next_tick: float, period: float) -> float:
    """When a pass that started at ``now`` should be followed by the next one: ``period`` later, but
    never before the next tick is due (nothing to step until then)."""
    return max(next_tick, now + period)


def _advance_together(bridges: Sequence[PtyBridge], step: Callable[[], None], now: float) -> None:
    """Step through every tick due at wall-clock time ``now``, each with every bridge's bytes."""
    lead = bridges[0]
    tick = lead.device.tick
    if now - lead._next_tick > lead.max_catch_up:  # too far behind: skip ticks, not race
        skipped = int((now - lead._next_tick) / tick)
        for bridge in bridges:
            bridge.skipped_ticks += skipped
            bridge._next_tick += skipped * tick
    while lead._next_tick <= now:
        for bridge in bridges:
            bridge._before_tick()
        step()
        for bridge in bridges:
            bridge._after_tick()
