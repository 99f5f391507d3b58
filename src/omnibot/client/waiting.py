"""Waiting on the link: pumping it until something happened, the retransmissions due meanwhile.

:class:`Waiting` is the client's layer above :mod:`~omnibot.client.receiving`: every wait (a reply,
IDLE, :meth:`Waiting.sleep`) reads the link in the caller's thread and dispatches what arrives.
Timeouts count on ``link.clock`` (simulated time on sim://) and raise LinkTimeout. In binary and
sequenced text the ARQ's sender has frames to send again in time, so the link is read in short
steps while commands wait (:data:`RETRY_POLL`), and a command's verdict may come after its
deadline: :meth:`Waiting._wait_for_verdict` waits for it within the ARQ's bound.
"""

from __future__ import annotations

import math
from collections.abc import Callable

from omnibot.client.pending import Pending
from omnibot.client.receiving import Receiving
from omnibot.errors import LinkTimeout
from omnibot.protocol import arq, codes

RETRY_POLL = codes.RETRY_TIMEOUT_MS / 2000.0
"""Binary and sequenced text: look at retransmissions this often (s)."""
_FOREVER_STEP = 1.0


class Waiting(Receiving):
    """pump, sleep, drain, wait_idle, and the waits the calls make."""

    def pump(self, timeout: float = 0.0) -> int:
        """Read what arrives within ``timeout`` s (0: only what is there), dispatch it; the number
        of messages handled."""
        return self._pump_once(timeout)

    def sleep(self, seconds: float) -> None:
        """Let ``seconds`` pass on the link's clock, dispatching events meanwhile."""
        deadline = self.clock.now() + seconds
        while (remaining := deadline - self.clock.now()) > 0:
            self._pump_once(remaining, gather=True)

    def drain(self, timeout: float | None = None) -> None:
        """Wait until every command sent has its reply (those that timed out excepted)."""
        waiting = [p for p in self._replies.waiting if not p.timed_out]
        if not waiting:
            return
        deadline = max(p.deadline for p in waiting) if timeout is None else self.clock.now() + timeout
        self._wait(lambda: all(p.done for p in waiting), deadline, "replies outstanding")

    def wait_idle(self, timeout: float | None = None) -> None:
        """Wait until the robot is idle: the replies of the commands sent are in and IDLE came
        (returns at once if it already did). ``timeout`` s on the link clock, None: no limit."""
        deadline = math.inf if timeout is None else self.clock.now() + timeout
        waiting = [p for p in self._replies.waiting if not p.timed_out]
        self._wait(lambda: all(p.done for p in waiting), deadline, "replies outstanding")
        self._wait(lambda: not self._moving, deadline, "robot still moving (no IDLE)")

    def _wait(self, done: Callable[[], bool], deadline: float, what: str) -> None:
        while not done():
            remaining = deadline - self.clock.now()
            if remaining <= 0:
                raise LinkTimeout(f"{what} (timeout on {self.link.url})")
            self._pump_once(min(remaining, _FOREVER_STEP), gather=True)

    def _pump_once(self, timeout: float, gather: bool = False) -> int:
        """Read within ``timeout`` s and dispatch. ``gather``: the caller acts only on what is
        dispatched (a wait, a sleep), so the read may gather the bytes until the wire can decode
        something (:meth:`~omnibot.client.wire.TextWire.gather`) while no frame waits for its
        retransmission (the sender's timer is serviced between reads)."""
        wire = self._wire
        sender = wire.sender
        if sender is not None:  # binary or sequenced text: retransmissions are due in time
            self._service()
            if self._replies.waiting:
                timeout = min(timeout, RETRY_POLL)
        until = wire.gather() if gather and (sender is None or sender.idle()) else None
        data = self._read(timeout, until)
        return self._process(data) if data else 0

    def _in_flight(self, pending: Pending) -> bool:
        """Binary or sequenced text: ``pending``'s frame is still in the send window (being sent
        again until its reply comes or the retries give up on it)."""
        sender = self._wire.sender
        return sender is not None and pending.seq in sender.pending()

    def _wait_for_verdict(self, pending: Pending) -> None:
        """Binary: wait until ``pending``'s frame is answered or given up on. A frame behind others
        gets its own retries only once it is the oldest, so it may outlive the call's deadline; a
        call that failed then by the clock would fail a command whose reply is still to come. The
        ARQ bounds the wait (each frame in the window at most one retry budget after the one
        before); LinkTimeout past that bound all the same."""
        sender = self._wire.sender
        assert sender is not None
        bound = self._arq_bound(sender)
        self._wait(lambda: pending.done or not self._in_flight(pending), bound, f"no reply to {pending.line}")
        if not pending.done:  # out of the window without a verdict (a SYNC frame abandoned it)
            raise LinkTimeout(f"no reply to {pending.line}; it may or may not have run")

    def _arq_bound(self, sender: arq.Sender) -> float:
        """When every frame now in ``sender``'s window is answered or given up on at the latest
        (each at most one retry budget after the one before it), on the link's clock."""
        return self.clock.now() + sender.window * (sender.budget_ms() / 1000.0 + RETRY_POLL)

    def _service(self) -> None:
        wire = self._wire
        if wire.sender is not None:
            for frame in wire.service(round(self.clock.now() * 1000)):
                self._write(frame)
            self._replies.give_up(wire.take_failed(), wire.sender.retries)
