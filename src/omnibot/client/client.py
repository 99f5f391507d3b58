"""RobotClient: typed calls in SI, request/reply matching, events, text or binary protocol.

The client is synchronous and pumps the link itself, in the caller's thread: no background
thread, so it runs unchanged on a lockstep ``sim://`` link (where a blocking read advances
simulated time) and on a real port. Every wait (a reply, IDLE, :meth:`RobotClient.sleep`) reads
the link and dispatches the events that arrive meanwhile to the listeners::

    move(0.5, 0.4) -> commands.move(): SI -> Move(50, 40, 0, 0), checked -> execute() -> submit()
        submit(): wire.frame() -> link.write() -> Pending (kept in send order)
        Pending.result(): pump until answered: link.read() -> wire.feed() -> replies / events
            replies: text -> the oldest Pending that accepts it (FIFO); binary -> by seq
            events:  RANGE WARN ERROR IDLE TEL HELLO(reset) -> Event -> listeners

Timeouts count on ``link.clock`` (simulated time on sim://) and raise LinkTimeout. A LinkError from
the link fails the call (and every command awaiting a reply); the client then tries
``link.reopen(retry=reconnect)`` so that the next call can work.

Text replies, tagged (docs/protocol.md, "Tags and checks"): before its first text command the client
asks the controller with a tagged ``HELLO#n*check`` whether it echoes tags (``tags=None``; True or
False skip the question). If it does, every command carries ``#tag*check`` and a reply is matched
by its tag alone, so a lost or late reply affects only its own command. With MODE bit 5 (sequenced
text, set with bit 4 before the first command) the tags are sequence numbers: a command whose reply
does not come is sent again (arq.Sender, as binary frames) and the controller answers the copy from
the reply it kept, so it runs once; without it (ERROR 39) the call raises LinkTimeout ("may or may
not have run") and later calls work. A reply whose check fails is dropped (an Unexpected event), so
no corrupted OK is ever taken for an answer. A controller that does not know tags (ERROR 23 to the
question, twice) gets today's untagged commands.

Untagged replies carry no sequence number: ``OK``/``ERROR`` answer the oldest untagged command
waiting, a ``STATUS`` or ``HELLO`` reply the oldest STATUS or HELLO (commands before it whose reply
never came fail with ProtocolError). An ``ERROR`` line while no command waits becomes an
:class:`~omnibot.client.events.ErrorEvent` (ERROR 26: a tagged command arrived corrupted and did
not run); a ``HELLO`` line nobody asked for is a controller reset
(:class:`~omnibot.client.events.ResetEvent`; waiting commands fail with ControllerReset). After an
untagged command timed out, the next call first resynchronises: it sends ``STATUS`` and waits for
that reply, which tells every earlier reply from the later ones.
The client owns its collaborators for these rules: a :class:`~omnibot.client.connection.Connection`
(the link's bytes, traced; failures and reopening), :class:`~omnibot.client.replies.Replies` (the
commands waiting and which one a reply answers) and :class:`~omnibot.client.switch.ProtocolSwitch`
(the protocol spoken, the MODE bits, text's tags and checks). Its own code is in layers, one concern
each (:mod:`omnibot.client.core`): ``receiving`` (replies and events), ``waiting`` (pumping),
``sending`` (commands out), ``listening`` (listeners and tracers), ``calls`` (the typed calls); this
module holds its public face: opening, its state, switching protocols, closing.

Not thread-safe: use a client from one thread (listeners run in that thread, during the waits).
"""

from __future__ import annotations

import contextlib
from types import TracebackType
from typing import Self

from omnibot.client import switch
from omnibot.client.calls import TypedCalls
from omnibot.client.connection import Connection
from omnibot.client.events import Listeners
from omnibot.client.limits import Limits
from omnibot.client.listening import Listening
from omnibot.client.pending import Pending
from omnibot.client.replies import Replies
from omnibot.client.sending import Sending
from omnibot.client.views import Hello
from omnibot.errors import LinkError, LinkTimeout
from omnibot.protocol import codes
from omnibot.robot import RobotDescription
from omnibot.transport import Link

DEFAULT_TIMEOUT = 1.0
"""Seconds (link clock) to wait for a reply."""


class RobotClient(Listening, Sending, TypedCalls):
    """A motor controller behind a :class:`~omnibot.transport.base.Link`, in SI units.

    ``robot`` (a description, preset name or file) adds the robot's limits to the checks made
    before sending; without it only the protocol's ranges are checked. ``timeout`` is the reply
    timeout in seconds of ``link.clock``; ``reconnect`` the seconds ``link.reopen`` may retry after
    a LinkError (None: do not reopen). ``tags``: text commands with ``#tag*check`` (True), without
    (False), or as the controller answers a tagged HELLO before the first command (None).
    ``text_window``: in text, the most bytes of commands sent and not yet answered (the flow control
    of docs/protocol.md, "Text flow control"; None or 0: no limit).
    """

    def __init__(
        self,
        link: Link,
        robot: RobotDescription | str | None = None,
        *,
        limits: Limits | None = None,
        timeout: float = DEFAULT_TIMEOUT,
        reconnect: float | None = 0.0,
        tags: bool | None = None,
        text_window: int | None = codes.TEXT_WINDOW,
    ) -> None:
        self._connection = Connection(link, reconnect, self._link_failed)
        self.text_window = text_window
        if limits is None:
            limits = Limits.from_robot(robot) if robot is not None else Limits()
        self.limits = limits
        self.timeout = timeout
        self.last_hello: Hello | None = None
        """The last HELLO seen (a reply or a reset greeting)."""
        self._preparing = ""
        self._heard = False
        self._listeners = Listeners()
        self._moving = False
        self._switch = switch.ProtocolSwitch(
            self,
            tags,
            write=self._write,
            read=self._read,
            ask=self._ask_probe,
            heard=lambda: self._heard,
            forget=lambda why: self._replies.fail_all(lambda p: LinkTimeout(f"no reply to {p.line}: {why}")),
        )
        self._replies = Replies(
            self, self._switch, self._listeners, complete=self._complete, event=self._event
        )

    @classmethod
    def open(
        cls, url: str, robot: RobotDescription | str | None = None, *, settle: float = 0.05, **options: object
    ) -> RobotClient:
        """Open ``url`` (see :func:`omnibot.transport.url.open_link`) and wrap it; for ``sim://PRESET``
        the robot defaults to that preset. ``options`` go to the constructor.

        The new link is read for ``settle`` seconds before the first command, so a controller's
        power-up ``HELLO`` (sim:// sends one at time 0) arrives as the greeting it is (a ResetEvent)
        and is not taken for the reply to a ``HELLO`` the caller sends next. Without a greeting,
        :meth:`find_protocol` runs: a controller left in binary mode is switched back to text."""
        from omnibot.transport import url as links  # its functions read when called (patchable)

        if robot is None:
            base = links.parse_link_url(url)[-1]
            if base.scheme == "sim":
                robot = base.target
        link = links.open_link(url)
        try:
            client = cls(link, robot, **options)  # type: ignore[arg-type]
            if settle > 0:
                client.sleep(settle)
            if client.last_hello is None:  # no greeting: the controller may be in binary mode
                with contextlib.suppress(LinkTimeout):  # nothing answers (yet): the first call says so
                    client.find_protocol()
            return client
        except BaseException:
            link.close()
            raise

    # ------------------------------------------------------------------ state

    @property
    def moving(self) -> bool:
        """True from the OK of a motion command until IDLE (or STOP, or a STATUS saying idle)."""
        return self._moving

    @property
    def broken(self) -> bool:
        """True after the link failed, until it is open again (the reopen after the failure did not
        work: the next call tries again first, or fails with reconnecting off)."""
        return self._connection.broken

    @property
    def mode_bits(self) -> int | None:
        """The MODE bits last set or reported by STATUS; None if not known yet."""
        return self._switch.mode

    @property
    def added_text_bits(self) -> int:
        """MODE bits 4 and 5 (checked, sequenced text) this client set on the controller, which had
        them clear."""
        return self._switch.added_text_bits

    @property
    def added_checked_text(self) -> bool:
        """This client set MODE bit 4 (checked text only) on the controller, which had it clear."""
        return self._switch.added_checked_text

    @property
    def sequenced(self) -> bool:
        """True while tagged text commands are sequence numbers the controller keeps (MODE bit 5):
        a command whose reply is lost is sent again and not run twice."""
        return self._switch.sequenced

    @property
    def outstanding(self) -> list[Pending]:
        """Commands sent whose reply has not come yet, oldest first."""
        return list(self._replies.waiting)

    @property
    def reconnect(self) -> float | None:
        """Seconds ``link.reopen`` may retry after a LinkError (None: do not reopen)."""
        return self._connection.reconnect

    @reconnect.setter
    def reconnect(self, seconds: float | None) -> None:
        self._connection.reconnect = seconds

    # ------------------------------------------------------------------ protocols

    def use_binary(self) -> Hello:
        """Switch to the binary protocol (MODE with bit 2, keeping the other bits), start the
        session with HELLO and return its reply (the protocol version in use). Works over a noisy
        line: each try is confirmed by a binary HELLO exchange (:mod:`omnibot.client.switch`)."""
        return self._switch.to_binary()

    def use_text(self) -> None:
        """Switch back to the text protocol (MODE with bit 2 clear, other bits kept); if the OK
        is lost, a probe tells which protocol the controller speaks."""
        self._switch.to_text()

    def find_protocol(self) -> None:
        """Ask the controller which protocol it speaks (a probe both protocols answer) and speak
        it; a controller found in binary mode (left there by a client that was killed) is
        switched back to text. Raises LinkTimeout if it never answers."""
        if self._switch.find_protocol() is not None:
            self._switch.to_text()

    # ------------------------------------------------------------------ lifetime

    def close(self) -> None:
        """Close the link (idempotent). The controller stays in its mode (see use_text)."""
        self._connection.close()

    def __enter__(self) -> Self:
        return self

    def __exit__(
        self, exc_type: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None
    ) -> None:
        self.close()

    def __repr__(self) -> str:
        proto = "binary" if self.binary else "text"
        return f"<RobotClient {self.link.url!r} {proto} outstanding={len(self._replies.waiting)}>"

    def _link_failed(self, exc: LinkError) -> None:
        """The link failed (the connection reopens it next): every command waiting fails with
        ``exc``, the protocol state is reset."""
        self._replies.fail_all(lambda p: exc)
        self._switch.link_failed()
        self._moving = False
        self._replies.link_failed()
