"""The page's requests on their way to the link thread: :class:`Inbox`, a bounded queue that never
drops an emergency stop or a page gone.

The web server (asyncio thread) puts each validated request in (:meth:`Inbox.offer`); the link thread
takes them all at each period (:meth:`Inbox.take`). Beyond :data:`INBOX_MAX` waiting, a request is
dropped (the server answers the page with an error), so a flood cannot grow memory or delay the link
thread by more than one bounded batch a period; an emergency stop or a page gone is flagged instead
and comes after the requests waiting, so nothing queued before it undoes it.
"""

from __future__ import annotations

import queue
import threading
from collections.abc import Iterator
from dataclasses import dataclass

from omnibot.web.messages import Drive, EStop, Joy, Resume, Teach

INBOX_MAX = 256
"""Requests waiting for the link thread; beyond it :meth:`Inbox.offer` drops them."""


@dataclass(frozen=True)
class PageGone:
    """A page disconnected: whatever it was driving is let go."""


Request = Drive | Joy | EStop | Resume | Teach | PageGone


class Inbox(queue.Queue[Request]):
    """The requests waiting for the link thread, at most :data:`INBOX_MAX`, and the flagged ones."""

    def __init__(self) -> None:
        super().__init__(maxsize=INBOX_MAX)
        self._estop_waiting = threading.Event()
        self._gone_waiting = threading.Event()

    def offer(self, request: Request) -> bool:
        """Queue ``request`` (thread-safe); False when the inbox is full and it was dropped. An
        emergency stop or a page gone is never dropped: with the inbox full it is flagged."""
        try:
            self.put_nowait(request)
        except queue.Full:
            if isinstance(request, EStop):
                self._estop_waiting.set()
                return True
            if isinstance(request, PageGone):
                self._gone_waiting.set()
                return True
            return False
        return True

    def take(self) -> Iterator[Request]:
        """The requests waiting, oldest first, then the flagged page gone and emergency stop."""
        while True:
            try:
                yield self.get_nowait()
            except queue.Empty:
                break
        if self._gone_waiting.is_set():
            self._gone_waiting.clear()
            yield PageGone()
        if self._estop_waiting.is_set():
            self._estop_waiting.clear()
            yield EStop(type="estop")
