"""Which command a reply answers: the commands a client sent and not answered yet (docs/protocol.md).

:class:`Replies` is the object a :class:`~omnibot.client.client.RobotClient` owns for it: the
commands waiting for a reply, oldest first, the tagged ones given up on (kept for a late reply), the
plain HELLOs the tag question still owes an answer to, and whether the untagged text replies are out
of step after a timeout. The client hands it each reply that arrives; it finds the command the reply
answers by the rules of the client's module docstring and hands the pair back to the client
(``complete``), or the reply, answering nothing, as an event (``event``):

* binary: by sequence number (:meth:`Replies.by_seq`); the commands before it that a SYNC frame
  abandoned fail;
* tagged text: by tag alone, wherever the command is in the line (:meth:`Replies.by_tag`), a command
  given up on included;
* untagged text: the oldest untagged command that accepts it (:meth:`Replies.in_order`); the ones
  before it, whose replies never came, fail. A HELLO line nobody asked for is the controller's
  reset, except when a plain HELLO of the tag question still owes its answer, or when it is the
  greeting of a controller that started as the client connected (reported, no command failed).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Protocol

from omnibot.client.events import Event, Listeners, ResetEvent, event_from_message
from omnibot.client.views import Hello
from omnibot.errors import LinkTimeout, ProtocolError
from omnibot.protocol.messages import ErrorReply, HelloReply, Reply

if TYPE_CHECKING:
    from omnibot.client.pending import Pending
    from omnibot.client.switch import ProtocolSwitch

LATE_MAX = 64
"""Tagged commands that timed out, kept so that a late reply still lands on them."""


class Host(Protocol):
    """What the replies ask of the client that owns them: the last HELLO it saw, which an owed HELLO's
    answer and a greeting update."""

    last_hello: Hello | None


class Replies:
    """The commands sent and not answered yet, and the reply matching of the client's protocol.

    ``host`` is the client, ``switch`` its :class:`~omnibot.client.switch.ProtocolSwitch` (the wire
    whose sender acknowledges what is answered; tags turned on by a tagged answer to the tag
    question), ``listeners`` its listeners (a greeting at connect goes straight to them);
    ``complete(pending, reply)`` records a command's reply, ``event(event)`` handles a reply that
    answers nothing as an event.
    """

    def __init__(
        self,
        host: Host,
        switch: ProtocolSwitch,
        listeners: Listeners,
        *,
        complete: Callable[[Pending, Reply], None],
        event: Callable[[Event], None],
    ) -> None:
        self._host = host
        self._switch = switch
        self._listeners = listeners
        self._complete = complete
        self._event = event
        self.waiting: list[Pending] = []
        """Commands sent whose reply has not come yet, oldest first."""
        self.out_of_step = False
        """Untagged text: a command timed out, so the client gets back in step before the next."""
        self._late: dict[int, Pending] = {}  # tag -> tagged command that timed out
        self._hellos_owed: list[float] = []  # link-clock deadlines of plain HELLOs the tag question sent
        self._synced = False  # text: a reply has been matched since the client started
        self._hello_answered = False  # text: the last reply matched was a HELLO reply

    # ------------------------------------------------------------------ what the client tells

    def owe_hello(self, deadline: float) -> None:
        """A plain HELLO of the tag question went out: its answer may come until ``deadline`` (link
        clock), and is no reset then."""
        self._hellos_owed.append(deadline)

    def timed_out(self, pending: Pending) -> None:
        """A call gave up on ``pending``: keep a tagged one aside for a late reply; after an
        untagged one, the text replies are out of step."""
        if self._switch.binary:
            return
        if pending.seq and not pending.probe:
            if pending in self.waiting:
                self.waiting.remove(pending)
            self._late[pending.seq] = pending
            while len(self._late) > LATE_MAX:
                del self._late[next(iter(self._late))]
        elif not pending.seq:
            self.out_of_step = True

    def fail_all(self, error: Callable[[Pending], BaseException]) -> None:
        """Fail every command still waiting for a reply with ``error(pending)``."""
        for p in self.waiting:
            p._fail(error(p))
        self.waiting.clear()

    def give_up(self, seqs: list[int], retries: int) -> None:
        """Fail the commands whose frames the ``retries`` retransmissions gave up on (sequence
        numbers ``seqs``)."""
        if not seqs:
            return
        for p in self.waiting:
            if p.seq in seqs:
                p._fail(
                    LinkTimeout(f"no reply to {p.line} after {retries} retries; it may or may not have run")
                )
        self.waiting = [p for p in self.waiting if not p.done]

    def controller_reset(self) -> None:
        """The controller restarted: no late reply and no earlier step is to be waited for."""
        self._late.clear()
        self.out_of_step = False

    def link_failed(self) -> None:
        """The link failed: a HELLO line may again be a greeting rather than a reset."""
        self._synced = False

    def room(self, size: int, window: int) -> bool:
        """Whether ``size`` more bytes fit in the text window of ``window`` bytes beside the unanswered
        commands (one command always goes when none is unanswered; a command that timed out no
        longer counts)."""
        busy = sum(p.size for p in self.waiting if not p.done and not p.timed_out)
        return busy == 0 or busy + size <= window

    # ------------------------------------------------------------------ matching

    def by_seq(self, seq: int, reply: Reply) -> None:
        """A binary reply answers the command with its sequence number."""
        sender = self._switch.wire.sender
        assert sender is not None
        sender.ack(seq)
        for i, p in enumerate(self.waiting):
            if p.seq == seq:
                for lost in self.waiting[:i]:
                    if lost.abandoned:
                        lost._fail(LinkTimeout(f"no reply to {lost.line}: abandoned by a SYNC frame"))
                self.waiting = [q for q in self.waiting[:i] if not q.done] + self.waiting[i + 1 :]
                self._complete(p, reply)
                return
        # a duplicate reply to a retransmitted command, or a late one: nothing waits for it

    def by_tag(self, tag: int, reply: Reply, now: float) -> None:
        """A tagged text reply answers the command with that tag, wherever it is in the line."""
        sender = self._switch.wire.sender
        waited = tag in self._late or any(p.seq == tag for p in self.waiting)
        if sender is not None and not sender.ack(tag) and not waited:
            return  # sequenced: the kept reply sent again for a command sent again, answered already
        for p in self.waiting:
            if p.seq == tag:
                self.waiting.remove(p)
                self._synced = True  # a reply matched: an untagged HELLO from now on is a reset
                self._hello_answered = False
                if p.probe:
                    self._switch.set_tags(True)
                if isinstance(reply, ErrorReply) or p.accepts(reply):
                    self._complete(p, reply)
                else:
                    p._fail(ProtocolError(f"{reply.keyword} is no reply to {p.line}"))
                return
        late = self._late.pop(tag, None)
        if late is not None and not late.done:  # its caller has had LinkTimeout: record what came
            self._complete(late, reply)
            return
        if isinstance(reply, HelloReply):
            # The late answer to a tagged HELLO given up (a probe): never a reset, whose greeting is
            # untagged; it does say that the controller echoes tags (a stale untagged line may have
            # answered the probes before it: taken for a reset, it made the client ask again forever).
            if self._switch.auto_tags:
                self._switch.set_tags(True)
            return
        self._event(event_from_message(reply, now))

    def in_order(self, reply: Reply, now: float) -> None:
        """An untagged text reply answers the oldest untagged command that accepts it."""
        waiting = [p for p in self.waiting if not p.seq or p.probe]  # the untagged ones
        for i, p in enumerate(waiting):
            if p.accepts(reply):
                for lost in waiting[:i]:
                    lost._fail(ProtocolError(f"no reply to {lost.line}: a later reply came first"))
                done = waiting[: i + 1]
                self.waiting = [q for q in self.waiting if q not in done]
                if isinstance(reply, HelloReply) and self._hellos_owed:
                    self._hellos_owed.pop(0)  # a plain HELLO of the tag question answered
                self._complete(p, reply)
                self._hello_answered = isinstance(reply, HelloReply)
                self._synced = True
                return
        event = event_from_message(reply, now)
        owed = [t for t in self._hellos_owed if t >= now]
        if isinstance(reply, HelloReply) and owed:
            # the answer to a plain HELLO of the tag question that another line was taken for (a
            # stale ERROR left on the line): not a reset
            owed.pop(0)
            self._hellos_owed = owed
            self._host.last_hello = Hello.from_reply(reply)
            return
        self._hellos_owed = owed
        if isinstance(event, ResetEvent) and (self._hello_answered or not self._synced):
            # The greeting of a controller that started as we connected (no reply matched yet), or
            # the HELLO line taken as the answer to our HELLO was the greeting and this is the
            # answer: report the reset, but the commands waiting may still be answered.
            self._hello_answered = False
            self._host.last_hello = event.hello
            self._listeners.dispatch(event)
            return
        self._event(event)
