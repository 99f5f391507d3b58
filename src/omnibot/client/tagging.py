"""Checked and sequenced text: whether the controller takes ``#tag*check`` and MODE bits 4 and 5.

:class:`TextTags` is the part of a client's :class:`~omnibot.client.switch.ProtocolSwitch` that
owns text's tags and checks (docs/protocol.md, "Tags and checks"): the tag question's verdict
(:meth:`TextTags.detect_tags`, asked with tagged HELLOs before the first text command), and MODE
bits 4 (checked text only) and 5 (sequenced text) asked for once tags are on
(:meth:`TextTags.require_checks`), with which of them this client set on a controller that had them
clear (the session guard clears them on the way out).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Final, Protocol

from omnibot.client.views import Hello
from omnibot.client.wire import TextWire, Wire
from omnibot.errors import ControllerError, LinkError, LinkTimeout
from omnibot.protocol import codes
from omnibot.protocol.messages import Command, ErrorReply, Mode, Reply
from omnibot.protocol.messages import Hello as HelloCommand

if TYPE_CHECKING:
    from omnibot.client.views import Status
    from omnibot.transport import Clock, Link

PROBE_TRIES: Final = 8
"""Rounds of tag questions before :meth:`ProtocolSwitch.detect_tags` gives up (LinkError)."""
UNTAGGED_VERDICT: Final = 3
"""Rounds in a row on a line proven clean that make a controller one without tags."""


class Host(Protocol):
    """What the switch asks of the client that owns it: its link, clock and reply timeout, its calls
    (matched replies), and the last HELLO it saw, which a probe's answer updates."""

    link: Link
    timeout: float
    last_hello: Hello | None

    @property
    def clock(self) -> Clock:
        """The link's clock."""

    def execute(self, command: Command, timeout: float | None = None) -> Reply:
        """Send ``command`` and wait for its reply."""

    def status(self) -> Status:
        """STATUS and its reply."""

    def hello(self, versions: tuple[int, ...] = ()) -> Hello:
        """HELLO and its reply."""

    def drain(self, timeout: float | None = None) -> None:
        """Wait for the replies of the commands sent."""


class TextTags:
    """Text's tags and checks, as far as the client knows them. ``tags`` as
    :class:`~omnibot.client.client.RobotClient`'s: text commands with ``#tag*check`` (True), without
    (False), or as the controller answers (None: asked with :meth:`detect_tags` before the first
    text command). The switch that it is part of provides the wire, the MODE bits and the client's
    questions (``ask``, ``heard``: see :class:`~omnibot.client.switch.ProtocolSwitch`)."""

    _host: Host
    _wire: Wire
    _mode: int | None
    _ask: Callable[[float, bool], Reply | None]
    _heard: Callable[[], bool]

    def __init__(self, tags: bool | None) -> None:
        self._auto_tags = tags is None
        self._tags = tags
        self._tags_seen = bool(tags)  # a tagged reply came (or tags were asked for): never fall back
        self._checks_asked = not tags and tags is not None  # MODE bits 4, 5 asked for (or never to be)
        self._added_text_bits = 0  # MODE bits 4 and 5 set on the controller, which had them clear

    @property
    def tags(self) -> bool | None:
        """True if text commands carry ``#tag*check``; None until the controller was asked."""
        return self._tags

    @property
    def auto_tags(self) -> bool:
        """Whether the client asks the controller if it takes tags (``tags=None``)."""
        return self._auto_tags

    @property
    def checks_wanted(self) -> bool:
        """Tags are on and MODE bits 4 and 5 still to be asked for (:meth:`require_checks`)."""
        return bool(self._tags) and not self._checks_asked

    @property
    def added_text_bits(self) -> int:
        """MODE bits 4 and 5 (checked, sequenced text) set on the controller, which had them clear."""
        return self._added_text_bits

    @property
    def added_checked_text(self) -> bool:
        """MODE bit 4 (checked text only) was set on the controller, which had it clear."""
        return bool(self._added_text_bits & codes.MODE_CHECKED_TEXT)

    def set_tags(self, on: bool | None) -> None:
        """Text commands with tags (True), without (False), or not known (None: ask again)."""
        self._tags = on
        self._tags_seen = self._tags_seen or bool(on)
        wire = self._wire
        if isinstance(wire, TextWire):
            wire.tags = bool(on)

    def hello_again(self) -> HelloCommand:
        """A HELLO that agrees on the protocol version agreed last (a bare one would say 2)."""
        hello = self._host.last_hello
        version = hello.version if hello is not None else codes.PROTOCOL_VERSION
        listed = tuple(v for v in codes.VERSIONS if v <= version)
        return HelloCommand(listed if version > codes.PROTOCOL_VERSION else ())

    def detect_tags(self, wait: float) -> None:
        """Ask with tagged HELLOs whether the controller takes tagged, checked text commands.

        A tagged reply says yes (a damaged line cannot forge its check), and so does ``ERROR,42`` (it
        runs checked text only). A controller without tags answers ``ERROR,23``, but so does one with
        them when the question arrived with its suffix damaged; so "no" takes :data:`UNTAGGED_VERDICT`
        rounds in a row of an untagged answer to the tagged question followed by the same answer to a
        plain ``HELLO`` (its HELLO reply, or ERROR 23 from a controller of seed 000's protocol) that
        proves the line clean. Silence, ERROR 26 or a differing answer starts the count again; no
        verdict after :data:`PROBE_TRIES` rounds is a LinkError, never a fall back. Once the client
        has had a tagged reply it never falls back: a controller that took tags and now refuses them
        is an error."""
        rounds = 0
        plain_answer: str | None = None
        answered_once = False
        for _ in range(PROBE_TRIES):
            reply = self._ask(wait, True)
            if self._tags is not None:
                return
            if reply is None:
                if not self._heard():  # not a byte from the controller yet: it is not there
                    break
                rounds = 0
                continue
            answered_once = True
            if isinstance(reply, ErrorReply) and reply.code == codes.E_CHECK_REQUIRED:
                self.set_tags(True)
                return
            if isinstance(reply, ErrorReply) and reply.code == codes.E_CHECKSUM:
                rounds = 0
                continue
            plain = self._ask(wait, False)
            if self._tags is not None:
                return
            answer = None if plain is None else type(plain).__name__ + str(getattr(plain, "code", ""))
            if answer is None or (plain_answer is not None and answer != plain_answer):
                rounds, plain_answer = 0, answer
                continue
            plain_answer = answer
            rounds += 1
            if rounds == UNTAGGED_VERDICT:
                if self._tags_seen:
                    raise LinkError(
                        f"the controller on {self._host.link.url} took tagged, checked commands before "
                        "and now refuses them (ERROR 23): another firmware? Reconnect to use it"
                    )
                self.set_tags(False)
                return
        if answered_once:
            raise LinkError(
                f"cannot tell whether the controller on {self._host.link.url} takes checked text commands: "
                f"{PROBE_TRIES} tagged HELLOs had no clear answer (a damaged line?)"
            )
        raise LinkTimeout(
            f"no reply to HELLO, sent to ask whether the controller takes tagged text commands "
            f"(timeout on {self._host.link.url})"
        )

    def require_checks(self, wait: float, probed: bool = False) -> None:
        """Tags are on: ask the controller to run only checked text commands (MODE bit 4), so that a
        line a damaged byte cuts short (a digit turned into ``;``) runs nothing, and to take their
        tags as sequence numbers (bit 5), so that a command sent again when its reply was lost is
        answered from the reply kept and not run twice; the client then sends again every tagged
        command whose reply does not come (as binary frames). A controller without bit 5 (ERROR 39:
        a firmware from before it) gets bit 4 alone and no command sent twice; one without bit 4
        neither bit and keeps running unchecked lines; nothing else changes.

        A tagged HELLO goes first (the tag question's, when it was just asked), as the sequence's
        first command: a controller left in sequenced text by a client that was killed starts its
        sequence afresh, so the STATUS after it is not taken for one out of order. HELLO and STATUS
        run nothing, so they are sent again as the sequence's commands are whether the controller
        keeps the sequence yet or not."""
        host = self._host
        wire = self._wire
        assert isinstance(wire, TextWire)
        wire.sequence(True)
        try:
            if not probed:
                host.execute(self.hello_again(), wait)
            mask = self._mode if self._mode is not None else host.status().mode
            for bits in (codes.MODE_CHECKED_TEXT | codes.MODE_SEQUENCED_TEXT, codes.MODE_CHECKED_TEXT):
                # set before it is sent: if its OK is lost the bits may be set, and the session guard
                # must clear them on the way out (clearing a bit that was never set changes nothing)
                self._added_text_bits = bits & ~mask
                if not bits & codes.MODE_SEQUENCED_TEXT:  # bit 4 alone: a command sent twice runs twice
                    wire.sequence(False)
                    if mask & bits == bits:
                        break
                try:
                    host.execute(Mode(mask | bits), wait)
                except ControllerError as exc:
                    if exc.code != codes.E_UNSUPPORTED:
                        raise
                    self._added_text_bits = 0  # a controller without the bit: nothing was set
                    continue
                break
        except BaseException:
            wire.sequence(False)
            raise
        self._checks_asked = True  # only now: a reply lost on the way asks again before the next command
