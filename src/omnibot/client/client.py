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

The client owns two collaborators for these rules: :class:`~omnibot.client.replies.Replies` (the
commands waiting and which one a reply answers) and :class:`~omnibot.client.switch.ProtocolSwitch`
(the protocol spoken, the MODE bits, text's tags and checks); its tracers (a recorder) are
:class:`~omnibot.client.tracing.Tracers`.

Not thread-safe: use a client from one thread (listeners run in that thread, during the waits).
"""

from __future__ import annotations

import contextlib
import math
from collections.abc import Callable
from types import TracebackType
from typing import Self, TypeVar

from omnibot.client import switch
from omnibot.client.calls import TypedCalls
from omnibot.client.errors import ControllerReset, controller_error
from omnibot.client.events import (
    ErrorEvent,
    Event,
    IdleEvent,
    Listeners,
    RangeEvent,
    ResetEvent,
    Telemetry,
    WarnEvent,
    event_from_message,
)
from omnibot.client.limits import Limits
from omnibot.client.pending import Pending
from omnibot.client.replies import Replies
from omnibot.client.tracing import Tracer, Tracers
from omnibot.client.views import Hello
from omnibot.client.wire import SYNC as SYNC_TEXT
from omnibot.client.wire import BinaryWire, TextWire, Wire
from omnibot.errors import ControllerError, LinkError, LinkTimeout, ProtocolError
from omnibot.protocol import arq, codes, linecheck, text
from omnibot.protocol.binary import Packet
from omnibot.protocol.messages import (
    Command,
    Delta,
    ErrorReply,
    HelloReply,
    Malformed,
    Mode,
    Move,
    Ok,
    Power,
    Reply,
    Rotate,
    StatusReply,
    Stop,
    Vel,
    check_command,
)
from omnibot.protocol.messages import Hello as HelloCommand
from omnibot.protocol.messages import Status as StatusCommand
from omnibot.protocol.messages import Telemetry as TelemetryMessage
from omnibot.robot import RobotDescription
from omnibot.transport import Clock, Link

E = TypeVar("E", bound=Event)

MOTION = (Move, Rotate, Delta, Power, Vel)
DEFAULT_TIMEOUT = 1.0
"""Seconds (link clock) to wait for a reply."""
RESYNC_TRIES = 3
"""Untagged text: STATUS exchanges tried at most to get back in step after a timeout."""
# binary and sequenced text: look at retransmissions this often (s)
_RETRY_POLL = codes.RETRY_TIMEOUT_MS / 2000.0
_SUFFIX_MAX = 1 + linecheck.TAG_DIGITS + 1 + linecheck.CHECK_DIGITS + 1  # "#tag", "*check" and "\n"
_FOREVER_STEP = 1.0


class RobotClient(TypedCalls):
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
        self.link = link
        self.text_window = text_window
        """Text: the most bytes of unanswered commands on the line (None or 0: no limit)."""
        if limits is None:
            limits = Limits.from_robot(robot) if robot is not None else Limits()
        self.limits = limits
        self.timeout = timeout
        self.reconnect = reconnect
        self.last_hello: Hello | None = None
        """The last HELLO seen (a reply or a reset greeting)."""
        self._preparing = ""  # the step before a text command under way: "probe" (tags?), "resync"
        self._heard = False  # a byte has come from the link
        self._listeners = Listeners()
        self._moving = False
        self._broken = False
        self._failure: LinkError | None = None  # why the link broke (told again if it stays broken)
        self._tracers = Tracers(self)
        self._switch = switch.ProtocolSwitch(
            self,
            tags,
            write=self._write,
            read=self._read,
            ask=self._ask_probe,
            heard=lambda: self._heard,
            forget=lambda why: self._replies.fail_all(lambda p: LinkTimeout(f"no reply to {p.line}: {why}")),
        )
        """The protocol spoken, the MODE bits, text's tags and checks; switching (client/switch.py)."""
        self._replies = Replies(
            self, self._switch, self._listeners, complete=self._complete, event=self._event
        )
        """The commands waiting for a reply and which one a reply answers (client/replies.py)."""

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
    def clock(self) -> Clock:
        """The link's clock: wall time, or simulated time on sim://."""
        return self.link.clock

    @property
    def binary(self) -> bool:
        """True while the client speaks the binary protocol."""
        return self._switch.binary

    @property
    def tags(self) -> bool | None:
        """True if text commands carry ``#tag*check``; None until the controller was asked."""
        return self._switch.tags

    @property
    def _wire(self) -> Wire:
        """The wire format in use (the switch's)."""
        return self._switch.wire

    @property
    def moving(self) -> bool:
        """True from the OK of a motion command until IDLE (or STOP, or a STATUS saying idle)."""
        return self._moving

    @property
    def broken(self) -> bool:
        """True after the link failed, until it is open again (the reopen after the failure did not
        work: the next call tries again first, or fails with reconnecting off)."""
        return self._broken

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

    # ------------------------------------------------------------------ listeners

    def add_listener(self, callback: Callable[[E], object], *types: type[E]) -> None:
        """Call ``callback(event)`` for each event of ``types`` (all events if none are given)."""
        self._listeners.add(callback, *types)

    def remove_listener(self, callback: Callable[[E], object]) -> None:
        """Stop calling ``callback`` (no error if it was not listening)."""
        self._listeners.remove(callback)

    def add_tracer(self, tracer: Tracer) -> None:
        """Hand ``tracer`` the link's bytes and the commands and replies (a recorder)."""
        self._tracers.add(tracer)

    def remove_tracer(self, tracer: Tracer) -> None:
        """Stop handing ``tracer`` anything."""
        self._tracers.remove(tracer)

    def on_telemetry(self, callback: Callable[[Telemetry], object]) -> None:
        """Call ``callback`` with every TEL sample."""
        self._listeners.add(callback, Telemetry)

    def on_range(self, callback: Callable[[RangeEvent], object]) -> None:
        """Call ``callback`` with every RANGE event."""
        self._listeners.add(callback, RangeEvent)

    def on_warn(self, callback: Callable[[WarnEvent], object]) -> None:
        """Call ``callback`` with every WARN event."""
        self._listeners.add(callback, WarnEvent)

    def on_error(self, callback: Callable[[ErrorEvent], object]) -> None:
        """Call ``callback`` with every ERROR event (a fault of the motion logic, not a rejected command)."""
        self._listeners.add(callback, ErrorEvent)

    def on_idle(self, callback: Callable[[IdleEvent], object]) -> None:
        """Call ``callback`` with every IDLE event (the queue ran empty, the motors stopped)."""
        self._listeners.add(callback, IdleEvent)

    def on_reset(self, callback: Callable[[ResetEvent], object]) -> None:
        """Call ``callback`` when the controller resets (its HELLO line arrives unasked)."""
        self._listeners.add(callback, ResetEvent)

    # ------------------------------------------------------------------ sending

    def execute(self, command: Command, timeout: float | None = None) -> Reply:
        """Send one command and wait for its reply (OK, STATUS or HELLO reply); ERROR raises."""
        return self.submit(command, timeout).result()

    def submit(self, command: Command, timeout: float | None = None) -> Pending:
        """Send one command without waiting: several may be outstanding (pipelining)."""
        check_command(command)
        return self._send(command, None, timeout)

    def submit_text(self, line: str, timeout: float | None = None) -> list[Pending]:
        """Send protocol text as typed (``"MOVE,2,40,0,0;DELTA,0,0,10,0,36"``), one Pending per
        non-empty command. In text mode each command goes out as written (bad ones too: the
        controller answers them); in binary mode they must parse, else ProtocolError."""
        try:
            data = line.encode("ascii") + b"\n"
        except UnicodeEncodeError:
            raise ProtocolError(f"commands are ASCII only: {line!r}") from None
        chunks: list[tuple[Command | None, bytes]] = []
        pos = 0
        while pos < len(data):
            used, parsed = text.decode_command(data[pos:])
            if used == 0:
                break
            chunk = data[pos : pos + used].rstrip(b";\r\n")
            pos += used
            if parsed is not None:
                chunks.append((None if isinstance(parsed, Malformed) else parsed, chunk))
        if self.binary:
            bad = [c.decode("latin-1") for cmd, c in chunks if cmd is None]
            if bad:
                raise ProtocolError(f"cannot send malformed commands in binary mode: {bad}")
            return [self.submit(cmd, timeout) for cmd, _ in chunks if cmd is not None]
        return [self._send(cmd, chunk, timeout, malformed=cmd is None) for cmd, chunk in chunks]

    def submit_raw(self, data: bytes, replies: int = 1, timeout: float | None = None) -> list[Pending]:
        """Write ``data`` unchanged (text mode only) and expect ``replies`` replies to it (OK,
        ERROR or STATUS; a HELLO line is never taken as the answer to raw bytes)."""
        if self.binary:
            raise ProtocolError("raw text cannot be sent in binary mode")
        self._ensure_open()
        self._wait_for_switch()
        line = data.decode("latin-1").strip()
        wait = self.timeout if timeout is None else timeout
        deadline = self.clock.now() + wait + self.link.line_time(len(data))
        out = [Pending(self, None, line, 0, deadline) for _ in range(replies)]
        self._replies.waiting.extend(out)
        self._write(data)
        return out

    def _send(
        self, command: Command | None, raw: bytes | None, timeout: float | None, malformed: bool = False
    ) -> Pending:
        """Send ``command``, or in text ``raw`` (one command as typed, without its terminator)."""
        self._ensure_open()
        self._wait_for_switch()
        wait = self.timeout if timeout is None else timeout
        if not self.binary:
            self._text_ready(command, raw, wait)
        wire = self._wire
        sender = wire.sender  # binary, or sequenced text (MODE bit 5): commands sent again until answered
        if sender is not None:  # the retransmissions answer or fail the call: wait for them
            wait = max(wait, sender.budget_ms() / 1000.0 + _RETRY_POLL)
        sync = isinstance(command, Stop | HelloCommand) or (
            isinstance(wire, TextWire) and isinstance(command, SYNC_TEXT)
        )
        if sender is not None and not sync and not wire.ready():
            # room comes when the oldest frame is answered or given up on: the ARQ's bound
            self._wait(wire.ready, self._arq_bound(sender), "send window full")
        if sender is not None and sync:
            self._replies.give_up(wire.take_failed(), sender.retries)
        window = self.text_window or 0
        if isinstance(wire, TextWire) and window and sender is not None:
            # a sequenced command is tracked for retransmission once framed: room first, for its
            # longest form (a tag of 4 digits)
            most = len(raw) + _SUFFIX_MAX if raw is not None else len(text.encode(command, tag=text.TAG_MAX))  # type: ignore[arg-type]
            self._wait(lambda: self._replies.room(most, window), self.clock.now() + wait, "text window full")
        now = self.clock.now()
        if raw is not None and isinstance(wire, TextWire):
            seq, data = wire.frame_raw(raw, round(now * 1000), isinstance(command, SYNC_TEXT))
        else:
            assert command is not None
            seq, data = wire.frame(command, round(now * 1000))
        if isinstance(wire, TextWire) and window and sender is None:
            self._wait(lambda: self._replies.room(len(data), window), now + wait, "text window full")
            now = self.clock.now()
        if sender is not None and sync:
            abandoned = set(wire.take_failed())
            for p in self._replies.waiting:
                p.abandoned = p.abandoned or p.seq in abandoned
        if raw is not None:
            line = raw.decode("latin-1").strip()
        else:
            assert command is not None
            line = text.encode(command).decode("ascii").strip()
        pending = Pending(self, command, line, seq, now + wait + self.link.line_time(len(data)), malformed)
        pending.size = len(data)
        self._replies.waiting.append(pending)
        if command is not None and self._tracers:
            self._tracers.message("command", command)
        self._write(data)
        return pending

    def _text_ready(self, command: Command | None, raw: bytes | None, wait: float) -> None:
        """Before a text command: learn whether the controller echoes tags (once), and get back in
        step after an untagged command timed out."""
        if self._preparing:
            return
        what = (text.encode(command) if command is not None else raw or b"").decode("latin-1").strip()
        probed = self.tags is None
        if probed:
            self._prepare("probe", self._switch.detect_tags, wait, what)
        if self._switch.checks_wanted:
            # a lost reply of the bits' setup leaves them to be asked again before the next command;
            # this one goes on (tagged and checked, as every command: only a cut line is not covered)
            with contextlib.suppress(LinkTimeout):
                self._prepare("checks", lambda w: self._switch.require_checks(w, probed), wait, what)
        sender = self._wire.sender
        if sender is not None and sender.needs_sync and not isinstance(command, SYNC_TEXT):
            # sequenced text after a give-up: the controller may still expect the tag given up on,
            # and only STOP, HELLO or MODE is taken whatever it expects (binary's SYNC flag)
            self._prepare("sync", lambda w: self.execute(self._switch.hello_again(), w), wait, what)
        if self._replies.out_of_step and not self.tags:
            self._prepare("resync", self._resync_now, wait, what)

    def _prepare(self, step: str, run: Callable[[float], object], wait: float, what: str) -> None:
        """Run a step before the text command ``what``: ``step`` names it while it runs (its own
        commands skip :meth:`_text_ready`); a timeout says that ``what`` was not sent."""
        self._preparing = step
        try:
            run(wait)
        except LinkTimeout as exc:
            raise LinkTimeout(f"{exc} ({what} was not sent)") from None
        finally:
            self._preparing = ""

    def _ask_probe(self, wait: float, tagged: bool) -> Reply | None:
        """One question of the switch's :meth:`~omnibot.client.switch.ProtocolSwitch.detect_tags`: a tagged HELLO (its untagged answer returned; a
        tagged one turns tags on) or a plain one; None when no answer came in ``wait`` s."""
        if tagged:
            wire = self._wire
            assert isinstance(wire, TextWire)
            tag, data = wire.frame(HelloCommand(), 0, tag=True)
        else:
            tag, data = 0, text.encode(HelloCommand())
        probe = Pending(self, HelloCommand(), data.decode("ascii").strip(), tag, self.clock.now() + wait)
        probe.probe = tagged
        self._replies.waiting.append(probe)
        if not tagged:
            self._replies.owe_hello(probe.deadline + wait)
        self._write(data)
        try:
            # a plain HELLO is waited for even when a tagged reply turns tags on meanwhile: its
            # untagged answer, coming later with nothing waiting for it, would be taken for a reset
            self._wait(lambda: probe.done or (tagged and self.tags is not None), probe.deadline, "")
        except LinkTimeout:
            self._replies.waiting.remove(probe)
            return None
        if probe in self._replies.waiting:
            self._replies.waiting.remove(probe)
        return probe.reply

    def _resync_now(self, wait: float) -> None:
        """Untagged text: give up the commands still waiting (their replies can no longer be told
        from later ones), then STATUS and its reply."""
        for _ in range(RESYNC_TRIES):
            self._pump_once(0.0)  # replies already here still land on their commands
            self._replies.fail_all(
                lambda p: LinkTimeout(
                    f"no reply to {p.line}: text replies out of step; it may or may not have run"
                )
            )
            try:
                self.submit(StatusCommand(), wait).result()
            except (LinkTimeout, ControllerError):
                continue
            self._replies.out_of_step = False
            return
        raise LinkTimeout(
            f"text replies out of step and no reply to STATUS after {RESYNC_TRIES} tries "
            f"(timeout on {self.link.url})"
        )

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
        return self.clock.now() + sender.window * (sender.budget_ms() / 1000.0 + _RETRY_POLL)

    def _wait_for_switch(self) -> None:
        """Wait for a MODE that switches protocols: nothing may be sent until its OK is in."""
        for p in list(self._replies.waiting):
            cmd = p.command
            if isinstance(cmd, Mode) and bool(cmd.mask & codes.MODE_BINARY) != self.binary and not p.done:
                p.result()

    # ------------------------------------------------------------------ waiting

    def pump(self, timeout: float = 0.0) -> int:
        """Read what arrives within ``timeout`` s (0: only what is there), dispatch it; the number
        of messages handled."""
        return self._pump_once(timeout)

    def sleep(self, seconds: float) -> None:
        """Let ``seconds`` pass on the link's clock, dispatching events meanwhile."""
        deadline = self.clock.now() + seconds
        while (remaining := deadline - self.clock.now()) > 0:
            self._pump_once(remaining)

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
            self._pump_once(min(remaining, _FOREVER_STEP))

    def _pump_once(self, timeout: float) -> int:
        if self._wire.sender is not None:  # binary or sequenced text: retransmissions are due in time
            self._service()
            if self._replies.waiting:
                timeout = min(timeout, _RETRY_POLL)
        data = self._read(timeout)
        return self._process(data) if data else 0

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

    # ------------------------------------------------------------------ input

    def _process(self, data: bytes) -> int:
        self._heard = True
        handled = 0
        while data:
            wire = self._wire
            items = wire.feed(data)
            data = b""
            for item in items:
                handled += 1
                self._handle(item)
                if self._wire is not wire:  # switched protocols (MODE) or the controller reset
                    data = wire.rest()
                    break
        return handled

    def _handle(self, item: Packet | Malformed) -> None:
        now = self.clock.now()
        if isinstance(item, Malformed):
            self._listeners.dispatch(event_from_message(item, now))
            return
        message = item.message
        if isinstance(message, HelloReply) and item.event:
            self._reset(event_from_message(message, now))
        elif isinstance(message, Ok | StatusReply | HelloReply) or (
            isinstance(message, ErrorReply) and not item.event
        ):
            if isinstance(self._wire, BinaryWire):
                self._replies.by_seq(item.seq, message)
            elif item.seq:
                self._replies.by_tag(item.seq, message, now)
            else:
                self._replies.in_order(message, now)
        else:
            wire = self._wire
            if isinstance(wire, BinaryWire) and not isinstance(message, TelemetryMessage):
                kind = wire.receiver.classify(item.seq, item.sync)  # seq 0: dropped
                if kind != arq.OUT_OF_ORDER:
                    self._write(wire.ack(item.seq))
                if kind != arq.NEW:
                    return
            self._event(event_from_message(message, now))

    def _complete(self, pending: Pending, reply: Reply) -> None:
        pending.reply = reply
        if self._tracers:
            self._tracers.message("reply", reply)
        if isinstance(reply, ErrorReply):
            pending.error = controller_error(reply.code, reply.description, pending.line)
            return
        command = pending.command
        if isinstance(reply, StatusReply):
            self._switch.mode_reported(reply.mode)
            self._moving = reply.state == codes.STATE_MOVING
        elif isinstance(reply, HelloReply):
            self.last_hello = Hello.from_reply(reply)
            if isinstance(self._wire, BinaryWire):
                self._wire.hello(reply)
        elif isinstance(command, MOTION):
            self._moving = True
        elif isinstance(command, Stop):
            self._moving = False
        elif isinstance(command, Mode):
            self._switch.mode_set(command.mask)

    def _event(self, event: Event) -> None:
        if isinstance(event, IdleEvent):
            self._moving = False
        elif isinstance(event, ResetEvent):
            self._reset(event)
            return
        self._listeners.dispatch(event)

    def _reset(self, event: Event) -> None:
        assert isinstance(event, ResetEvent)
        self.last_hello = event.hello
        self._replies.fail_all(
            lambda p: ControllerReset(f"the controller restarted before answering {p.line}")
        )
        self._moving = False
        self._replies.controller_reset()
        # perhaps another firmware now: ask for tags again (not while asking)
        self._switch.controller_reset(ask_tags=self._preparing != "probe")
        self._listeners.dispatch(event)

    # ------------------------------------------------------------------ link

    def _service(self) -> None:
        wire = self._wire
        if wire.sender is not None:
            for frame in wire.service(round(self.clock.now() * 1000)):
                self._write(frame)
            self._replies.give_up(wire.take_failed(), wire.sender.retries)

    def _write(self, data: bytes) -> None:
        if self._tracers:
            self._tracers.link_bytes("TX", data)
        try:
            self.link.write(data)
        except LinkError as exc:
            self._tracers.link_bytes("ERR", note=str(exc))
            self._link_failed(exc)
            raise

    def _read(self, timeout: float) -> bytes:
        try:
            data = self.link.read(4096, timeout)
        except LinkError as exc:
            self._tracers.link_bytes("ERR", note=str(exc))
            self._link_failed(exc)
            raise
        if data and self._tracers:
            self._tracers.link_bytes("RX", data)
        return data

    def _link_failed(self, exc: LinkError) -> None:
        self._replies.fail_all(lambda p: exc)
        self._switch.link_failed()
        self._moving = False
        self._broken = True
        self._failure = exc
        self._replies.link_failed()
        if self.reconnect is not None and not self.link.closed:
            try:
                self.link.reopen(retry=self.reconnect)
                self._broken = False
            except LinkError:
                pass

    def _ensure_open(self) -> None:
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

    # ------------------------------------------------------------------ lifetime

    def close(self) -> None:
        """Close the link (idempotent). The controller stays in its mode (see use_text)."""
        if self._tracers and not self.link.closed:
            self._tracers.link_bytes("CLOSE")
        self.link.close()

    def __enter__(self) -> Self:
        return self

    def __exit__(
        self, exc_type: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None
    ) -> None:
        self.close()

    def __repr__(self) -> str:
        proto = "binary" if self.binary else "text"
        return f"<RobotClient {self.link.url!r} {proto} outstanding={len(self._replies.waiting)}>"
