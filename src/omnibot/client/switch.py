r"""The protocol the client speaks: finding and switching it, also over a noisy line (docs/protocol.md).

:class:`ProtocolSwitch` is the object a :class:`~omnibot.client.client.RobotClient` owns for it: the
wire in use (text or binary), the controller's MODE bits as the client knows them, and text's tags
and checks (whether commands carry ``#tag*check``: the tag question's verdict, MODE bits 4 and 5 set
by this client, sequenced text: :class:`~omnibot.client.tagging.TextTags`, which it is built on).
The client tells it what happened (a MODE or STATUS answered, a reset, a failed link) and asks it to
switch; the switch talks to the controller through the client's calls and the bytes
functions the client hands it, and writes none of the client's fields.

Text has no check, so any text exchange may be lost or changed on the way; the binary HELLO
exchange cannot be changed unseen. Each step therefore ends in a question the controller can only
answer one way per protocol, the *probe* (docs/protocol.md, "Switching and version negotiation")::

    host:        00 HELLO frame (SYNC, our versions) 00 ; CR LF
    binary controller:  HELLO reply frame (the session starts; ";\r\n" is garbage before the next frame)
    text controller:    ERROR lines for the garbage (or its HELLO greeting if it just reset)

* :meth:`ProtocolSwitch.find_protocol`: probe until one of the answers comes (waiting longer for
  each probe: a slow or loaded line answers late); the client then speaks what the controller speaks
  (used on connect when no greeting came, and after a switch went wrong). A text answer ends with a
  STATUS exchange: the ERROR lines owed to earlier probes come before its reply and are dropped with
  it, so none is taken for the answer to a later command.
* :meth:`ProtocolSwitch.to_binary`: read the MODE bits (two text STATUS replies that agree), send
  ``MODE,<bits|4>``, probe until an answer comes; send MODE again while the answer is text; then
  check the bits with a binary STATUS and set them again if a corrupted MODE changed them.
* :meth:`ProtocolSwitch.to_text`: the binary MODE frame with bit 2 clear; if its OK frame never
  comes, probe. Then a STATUS exchange as after a probe: a reply slower than the retry time had the
  MODE frame sent again, and each copy reached a text controller as ERROR lines (and as a partial
  line that would have spoilt the next command).

Each works on the client's link directly (no Pending, no reply matching), so what a lost
text reply leaves behind cannot confuse it; it fails the commands still waiting when it starts.
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable
from typing import Final

from omnibot.client.tagging import Host, TextTags
from omnibot.client.views import Hello
from omnibot.client.wire import BinaryWire, TextWire, Wire
from omnibot.errors import LinkTimeout, ProtocolError
from omnibot.protocol import codes, linecheck, text
from omnibot.protocol.binary import Packet
from omnibot.protocol.messages import (
    HELLO_WITHOUT_WINDOW,
    ErrorReply,
    HelloReply,
    Malformed,
    Mode,
    Ok,
    Reply,
    StatusReply,
    predates_window,
)
from omnibot.protocol.messages import Hello as HelloCommand

ATTEMPTS: Final = 8
"""MODE commands (to_binary, to_text) and probes (find_protocol) tried before giving up."""
PROBES: Final = 3
"""Probes after each MODE command of to_binary."""
ANSWER_TIME: Final = 0.1
"""Seconds (link clock) to wait for the answer to the first probe or to one text command."""
ANSWER_TIME_MAX: Final = 0.8
"""Seconds (link clock) a later probe waits at most: each waits twice as long as the one before."""
_QUIET: Final = 0.02


class ProtocolSwitch(TextTags):
    """The protocol a client speaks and the controller's MODE bits as far as the client knows them.

    ``host`` is the client; ``write`` and ``read`` its link's bytes (traced, a failure handled as
    the client handles it); ``ask(wait, tagged)`` sends a HELLO, tagged or not, and returns the
    untagged answer matched to it (None: none in ``wait`` s; a tagged answer turns tags on);
    ``heard()`` whether a byte has come from the link; ``forget(why)`` fails the commands still
    waiting for a reply. ``tags`` as :class:`~omnibot.client.client.RobotClient`'s: text commands
    with ``#tag*check`` (True), without (False), or as the controller answers (None: asked with
    :meth:`detect_tags` before the first text command).
    """

    def __init__(
        self,
        host: Host,
        tags: bool | None,
        *,
        write: Callable[[bytes], None],
        read: Callable[[float], bytes],
        ask: Callable[[float, bool], Reply | None],
        heard: Callable[[], bool],
        forget: Callable[[str], None],
    ) -> None:
        self._host = host
        self._write = write
        self._read = read
        self._ask = ask
        self._heard = heard
        self._forget = forget
        self._wire: Wire = TextWire(bool(tags))
        self._mode: int | None = None
        super().__init__(tags)

    # ------------------------------------------------------------------ state

    @property
    def wire(self) -> Wire:
        """The wire format in use: text or binary."""
        return self._wire

    @property
    def binary(self) -> bool:
        """True while the client speaks the binary protocol."""
        return self._wire.binary

    @property
    def mode(self) -> int | None:
        """The MODE bits last set or reported by STATUS; None if not known yet."""
        return self._mode

    @property
    def sequenced(self) -> bool:
        """True while tagged text commands are sequence numbers the controller keeps (MODE bit 5)."""
        return isinstance(self._wire, TextWire) and self._wire.sender is not None

    # ------------------------------------------------------------------ what the client saw

    def mode_reported(self, mask: int) -> None:
        """A STATUS reply gave the MODE bits."""
        self._mode = mask

    def mode_set(self, mask: int) -> None:
        """A MODE command was answered OK: the bits are ``mask``, and the wire follows bits 2 and 5."""
        self._mode = mask
        binary = bool(mask & codes.MODE_BINARY)
        wire = self._wire
        sequenced = bool(mask & codes.MODE_SEQUENCED_TEXT and self._tags)
        if isinstance(wire, TextWire) and not binary and sequenced != (wire.sender is not None):
            wire.sequence(sequenced)  # set by hand: the next command a sync one (a HELLO)
        if binary != self.binary:
            # back in text the controller starts its sequence afresh (it reset it when it
            # switched): the sender's first command is a sync one
            self._wire = BinaryWire() if binary else self._text_wire(sequenced)

    def controller_reset(self, ask_tags: bool) -> None:
        """The controller restarted: its MODE bits are cleared (text, no checks) and, when
        ``ask_tags`` and the client asks, the tags are to be asked for again (another firmware?)."""
        self._mode = None
        if self._auto_tags and ask_tags:
            self.set_tags(None)
        self._checks_asked = self._tags is False  # the restart cleared MODE bits 4, 5: ask again
        if isinstance(self._wire, TextWire):
            self._wire.sequence(False)
        else:
            self._wire = self._text_wire(False)

    def link_failed(self) -> None:
        """The link failed: a fresh wire of the same protocol, and the text bits asked for again
        (perhaps the controller restarted)."""
        self._wire = BinaryWire() if self.binary else self._text_wire(False)
        self._checks_asked = self._tags is False

    def _text_wire(self, sequenced: bool) -> TextWire:
        """A new text wire, its tags going on from the last one's (sequenced: MODE bit 5 is set)."""
        wire = self._wire
        text_wire = TextWire(bool(self._tags), wire.last_tag if isinstance(wire, TextWire) else 0)
        text_wire.sequence(sequenced and bool(self._tags))  # its first command: a sync one (a HELLO)
        return text_wire

    # ------------------------------------------------------------------ text and binary

    def find_protocol(self, attempts: int = ATTEMPTS) -> Hello | None:
        """Probe until the controller answers: binary -> the client speaks binary, a session has
        started and its HELLO is returned; text -> the client speaks text, None. Raises LinkTimeout
        if no probe got an answer."""
        self._forget("the client is probing the controller's protocol")
        window = ANSWER_TIME
        for _ in range(attempts):
            found = self._probe(window)
            if isinstance(found, Hello):
                return found
            if found is False:
                self._skip_owed_text()
                return None
            window = min(2.0 * window, ANSWER_TIME_MAX)
        raise LinkTimeout(f"the controller answered none of {attempts} probes (on {self._host.link.url})")

    def to_binary(self) -> Hello:
        """Switch to binary (other MODE bits kept) and start the session; returns its HELLO."""
        host = self._host
        if self.binary:
            return host.hello(codes.VERSIONS)
        hello = host.last_hello
        if hello is not None and hello.version not in codes.VERSIONS:
            raise ProtocolError(
                f"the controller speaks protocol version {hello.version}; binary mode needs one of {codes.VERSIONS}"
            )
        with contextlib.suppress(LinkTimeout):  # a reply lost on the way: nothing waits for it now
            host.drain()
        self._forget("the client is switching to binary")
        mask = self._mode if self._mode is not None else self._read_mode()
        wanted = mask | codes.MODE_BINARY
        for _ in range(ATTEMPTS):
            self._text_exchange(f"MODE,{wanted}\n".encode(), (Ok, ErrorReply))
            try:
                found = self.find_protocol(PROBES)
            except LinkTimeout:
                continue  # no probe answered: send MODE again (a binary controller drops it)
            if found is not None:
                status = host.status()
                if status.mode != wanted:  # the MODE line was corrupted into other bits
                    host.execute(Mode(wanted))
                self._mode = wanted
                return found
        raise LinkTimeout(
            f"the controller did not switch to binary after {ATTEMPTS} tries (on {host.link.url})"
        )

    def to_text(self) -> None:
        """Switch back to text (MODE frame with bit 2 clear, other bits kept)."""
        host = self._host
        for _ in range(ATTEMPTS):
            if not self.binary:
                return
            mask = self._mode if self._mode is not None else host.status().mode
            try:
                host.execute(Mode(mask & ~codes.MODE_BINARY))
            except LinkTimeout:  # the OK frame was lost, or the MODE frame: which one, ask
                self.find_protocol()
            else:
                self._skip_owed_text()
                return
        raise LinkTimeout(
            f"the controller did not switch to text after {ATTEMPTS} tries (on {host.link.url})"
        )

    def _probe(self, window: float = ANSWER_TIME) -> Hello | bool | None:
        """One probe: the Hello of a binary controller (the client now speaks binary), False for a
        text controller (the client speaks text; the answers that came are read and dropped), None
        if no answer came within ``window`` s."""
        host = self._host
        wire = BinaryWire()
        clock = host.clock
        seq, frame = wire.frame(HelloCommand(codes.VERSIONS), round(clock.now() * 1000))
        self._write(frame + b";\r\n")
        lines = text.TextDecoder()
        deadline = clock.now() + window
        text_seen = False
        while (remaining := deadline - clock.now()) > 0:
            data = self._read(min(remaining, _QUIET) if text_seen else remaining)
            if not data:
                if text_seen:
                    break  # the ERROR lines for the probe are in
                continue
            for item in wire.feed(data):
                if isinstance(item, Malformed) and item.reason == HELLO_WITHOUT_WINDOW:
                    raise ProtocolError(HELLO_WITHOUT_WINDOW)  # binary, but no session this host can run
                if not isinstance(item, Packet) or item.event or item.seq != seq:
                    continue
                if isinstance(item.message, HelloReply):
                    known = host.last_hello
                    if known is not None and predates_window(item.message, known.name):
                        raise ProtocolError(HELLO_WITHOUT_WINDOW)
                    wire.sender.ack(seq)
                    wire.hello(item.message)
                    self._wire = wire
                    self._mode = None
                    host.last_hello = Hello.from_reply(item.message)
                    return host.last_hello
            for message in lines.feed(data):
                if isinstance(message, ErrorReply | HelloReply):
                    text_seen = True
                    if isinstance(message, HelloReply):
                        host.last_hello = Hello.from_reply(message)
        if text_seen:
            self._wire = self._text_wire(bool((self._mode or 0) & codes.MODE_SEQUENCED_TEXT))
            return False
        return None

    def _skip_owed_text(self) -> None:
        """Read up to the reply of a STATUS sent now: the text a controller still owes comes before it
        (it answers in order) and is dropped. A probe gets two ERROR lines from a text controller, and
        those sent before the one answered are owed still on a line slower than their wait; a binary
        frame sent again after the switch to text (its OK slower than the retry time) gets ERROR lines
        too, and leaves a partial line, which the LF in front of STATUS ends. Taken for the answer to
        the next command instead (in text nothing tells them apart, and tags are not known yet after
        a probe), they failed it. Each STATUS waits the client's reply timeout; LinkTimeout if none is
        answered."""
        for _ in range(ATTEMPTS):
            if self._text_exchange(b"\nSTATUS\n", (StatusReply,), self._host.timeout) is not None:
                return
        raise LinkTimeout(
            f"the controller answered none of {ATTEMPTS} STATUS in text (on {self._host.link.url})"
        )

    def _read_mode(self) -> int:
        """The MODE bits from text STATUS replies: two that agree (a corrupted digit rarely repeats)."""
        seen: list[int] = []
        for _ in range(3 * ATTEMPTS):
            reply = self._text_exchange(b"STATUS\n", (StatusReply,))
            if isinstance(reply, StatusReply):
                if reply.mode in seen:
                    return reply.mode
                seen.append(reply.mode)
        raise LinkTimeout(f"no two STATUS replies agreed on the MODE bits (on {self._host.link.url})")

    def _text_exchange(
        self, line: bytes, kinds: tuple[type, ...], wait: float = ANSWER_TIME
    ) -> object | None:
        """Write one text command and read until a reply of ``kinds`` (returned) or ``wait`` s. With
        tags on the command carries a ``*`` check (no tag: its reply is matched here, not by the
        client), which a controller that runs only checked text (MODE bit 4) asks for."""
        if self._tags:
            body = line.strip(b"\n")
            line = line[: line.index(body)] + body + linecheck.suffix(body, None, True) + b"\n"
        self._write(line)
        lines = text.TextDecoder()
        clock = self._host.clock
        deadline = clock.now() + wait
        while (remaining := deadline - clock.now()) > 0:
            data = self._read(remaining)
            for message in lines.feed(data):
                if isinstance(message, kinds):
                    return message
        return None
