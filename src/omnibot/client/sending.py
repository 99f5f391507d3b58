"""Sending commands: framing, the send window, and the steps before a text command.

:class:`Sending` is the client's layer above :mod:`~omnibot.client.waiting`. A command is framed by
the wire in use and kept as a :class:`~omnibot.client.pending.Pending` in send order; with a sender
(binary, sequenced text) it waits for room in the ARQ's window, in text for room in the text window
(docs/protocol.md, "Text flow control"). Before a text command the client may first have to ask
whether the controller takes tags (the switch's
:meth:`~omnibot.client.switch.ProtocolSwitch.detect_tags`), set MODE bits 4 and 5, send a sync
HELLO after a give-up, or get back in step after an untagged command timed out (STATUS).
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable

from omnibot.client.pending import Pending
from omnibot.client.waiting import RETRY_POLL, Waiting
from omnibot.client.wire import SYNC as SYNC_TEXT
from omnibot.client.wire import TextWire
from omnibot.errors import ControllerError, LinkTimeout, ProtocolError
from omnibot.protocol import codes, linecheck, text
from omnibot.protocol.messages import Command, Malformed, Mode, Reply, Stop, check_command
from omnibot.protocol.messages import Hello as HelloCommand
from omnibot.protocol.messages import Status as StatusCommand

RESYNC_TRIES = 3
"""Untagged text: STATUS exchanges tried at most to get back in step after a timeout."""
_SUFFIX_MAX = 1 + linecheck.TAG_DIGITS + 1 + linecheck.CHECK_DIGITS + 1  # "#tag", "*check" and "\n"


class Sending(Waiting):
    """execute, submit, submit_text, submit_raw, and what a command needs before it goes out."""

    text_window: int | None
    """Text: the most bytes of unanswered commands on the line (None or 0: no limit)."""

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
        self._connection.ensure_open()
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
        self._connection.ensure_open()
        self._wait_for_switch()
        wait = self.timeout if timeout is None else timeout
        if not self.binary:
            self._text_ready(command, raw, wait)
        wire = self._wire
        sender = wire.sender  # binary, or sequenced text (MODE bit 5): commands sent again until answered
        if sender is not None:  # the retransmissions answer or fail the call: wait for them
            wait = max(wait, sender.budget_ms() / 1000.0 + RETRY_POLL)
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

    def _wait_for_switch(self) -> None:
        """Wait for a MODE that switches protocols: nothing may be sent until its OK is in."""
        for p in list(self._replies.waiting):
            cmd = p.command
            if isinstance(cmd, Mode) and bool(cmd.mask & codes.MODE_BINARY) != self.binary and not p.done:
                p.result()
