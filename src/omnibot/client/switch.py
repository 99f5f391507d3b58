r"""Finding and switching the controller's protocol, also over a noisy line (docs/protocol.md).

Text has no check, so any text exchange may be lost or changed on the way; the binary HELLO
exchange cannot be changed unseen. Each step therefore ends in a question the controller can only
answer one way per protocol, the *probe* (docs/protocol.md, "Switching and version negotiation")::

    host:        00 HELLO frame (SYNC, our versions) 00 ; CR LF
    binary controller:  HELLO reply frame (the session starts; ";\r\n" is garbage before the next frame)
    text controller:    ERROR lines for the garbage (or its HELLO greeting if it just reset)

* :func:`find_protocol`: probe until one of the answers comes (waiting longer for each probe: a
  slow or loaded line answers late); the client then speaks what the controller speaks (used on
  connect when no greeting came, and after a switch went wrong). A text answer ends with a STATUS
  exchange: the ERROR lines owed to earlier probes come before its reply and are dropped with it, so
  none is taken for the answer to a later command.
* :func:`to_binary`: read the MODE bits (two text STATUS replies that agree), send ``MODE,<bits|4>``,
  probe until an answer comes; send MODE again while the answer is text; then check the bits with
  a binary STATUS and set them again if a corrupted MODE changed them.
* :func:`to_text`: the binary MODE frame with bit 2 clear; if its OK frame never comes, probe.
  Then a STATUS exchange as after a probe: a reply slower than the retry time had the MODE frame
  sent again, and each copy reached a text controller as ERROR lines (and as a partial line that
  would have spoilt the next command).

Each function works on the client's link directly (no Pending, no reply matching), so what a lost
text reply leaves behind cannot confuse it; it fails the commands still waiting when it starts.
"""

from __future__ import annotations

import contextlib
from typing import TYPE_CHECKING, Final

from omnibot.client.views import Hello
from omnibot.client.wire import BinaryWire
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
    StatusReply,
    predates_window,
)
from omnibot.protocol.messages import Hello as HelloCommand

if TYPE_CHECKING:
    from omnibot.client.client import RobotClient

ATTEMPTS: Final = 8
"""MODE commands (to_binary, to_text) and probes (find_protocol) tried before giving up."""
PROBES: Final = 3
"""Probes after each MODE command of to_binary."""
ANSWER_TIME: Final = 0.1
"""Seconds (link clock) to wait for the answer to the first probe or to one text command."""
ANSWER_TIME_MAX: Final = 0.8
"""Seconds (link clock) a later probe waits at most: each waits twice as long as the one before."""
_QUIET: Final = 0.02


def find_protocol(client: RobotClient, attempts: int = ATTEMPTS) -> Hello | None:
    """Probe until the controller answers: binary -> the client speaks binary, a session has
    started and its HELLO is returned; text -> the client speaks text, None. Raises LinkTimeout
    if no probe got an answer."""
    _forget_waiting(client, "the client is probing the controller's protocol")
    window = ANSWER_TIME
    for _ in range(attempts):
        found = _probe(client, window)
        if isinstance(found, Hello):
            return found
        if found is False:
            _skip_owed_text(client)
            return None
        window = min(2.0 * window, ANSWER_TIME_MAX)
    raise LinkTimeout(f"the controller answered none of {attempts} probes (on {client.link.url})")


def to_binary(client: RobotClient) -> Hello:
    """Switch to binary (other MODE bits kept) and start the session; returns its HELLO."""
    if client.binary:
        return client.hello(codes.VERSIONS)
    hello = client.last_hello
    if hello is not None and hello.version not in codes.VERSIONS:
        raise ProtocolError(
            f"the controller speaks protocol version {hello.version}; binary mode needs one of {codes.VERSIONS}"
        )
    with contextlib.suppress(LinkTimeout):  # a reply lost on the way: nothing waits for it now
        client.drain()
    _forget_waiting(client, "the client is switching to binary")
    mask = client.mode_bits if client.mode_bits is not None else _read_mode(client)
    wanted = mask | codes.MODE_BINARY
    for _ in range(ATTEMPTS):
        _text_exchange(client, f"MODE,{wanted}\n".encode(), (Ok, ErrorReply))
        try:
            found = find_protocol(client, PROBES)
        except LinkTimeout:
            continue  # no probe answered: send MODE again (a binary controller drops it)
        if found is not None:
            status = client.status()
            if status.mode != wanted:  # the MODE line was corrupted into other bits
                client.execute(Mode(wanted))
            client._mode = wanted
            return found
    raise LinkTimeout(
        f"the controller did not switch to binary after {ATTEMPTS} tries (on {client.link.url})"
    )


def to_text(client: RobotClient) -> None:
    """Switch back to text (MODE frame with bit 2 clear, other bits kept)."""
    for _ in range(ATTEMPTS):
        if not client.binary:
            return
        mask = client.mode_bits if client.mode_bits is not None else client.status().mode
        try:
            client.execute(Mode(mask & ~codes.MODE_BINARY))
        except LinkTimeout:  # the OK frame was lost, or the MODE frame: which one, ask
            find_protocol(client)
        else:
            _skip_owed_text(client)
            return
    raise LinkTimeout(f"the controller did not switch to text after {ATTEMPTS} tries (on {client.link.url})")


# ---------------------------------------------------------------------------------------------------
def _probe(client: RobotClient, window: float = ANSWER_TIME) -> Hello | bool | None:
    """One probe: the Hello of a binary controller (the client now speaks binary), False for a
    text controller (the client speaks text; the answers that came are read and dropped), None
    if no answer came within ``window`` s."""
    wire = BinaryWire()
    clock = client.clock
    seq, frame = wire.frame(HelloCommand(codes.VERSIONS), round(clock.now() * 1000))
    client._write(frame + b";\r\n")
    lines = text.TextDecoder()
    deadline = clock.now() + window
    text_seen = False
    while (remaining := deadline - clock.now()) > 0:
        data = client._read(min(remaining, _QUIET) if text_seen else remaining)
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
                known = client.last_hello
                if known is not None and predates_window(item.message, known.name):
                    raise ProtocolError(HELLO_WITHOUT_WINDOW)
                wire.sender.ack(seq)
                wire.hello(item.message)
                client._wire = wire
                client._mode = None
                client.last_hello = Hello.from_reply(item.message)
                return client.last_hello
        for message in lines.feed(data):
            if isinstance(message, ErrorReply | HelloReply):
                text_seen = True
                if isinstance(message, HelloReply):
                    client.last_hello = Hello.from_reply(message)
    if text_seen:
        client._wire = client._text_wire(bool((client.mode_bits or 0) & codes.MODE_SEQUENCED_TEXT))
        return False
    return None


def _skip_owed_text(client: RobotClient) -> None:
    """Read up to the reply of a STATUS sent now: the text a controller still owes comes before it
    (it answers in order) and is dropped. A probe gets two ERROR lines from a text controller, and
    those sent before the one answered are owed still on a line slower than their wait; a binary
    frame sent again after the switch to text (its OK slower than the retry time) gets ERROR lines
    too, and leaves a partial line, which the LF in front of STATUS ends. Taken for the answer to
    the next command instead (in text nothing tells them apart, and tags are not known yet after
    a probe), they failed it. Each STATUS waits the client's reply timeout; LinkTimeout if none is
    answered."""
    for _ in range(ATTEMPTS):
        if _text_exchange(client, b"\nSTATUS\n", (StatusReply,), client.timeout) is not None:
            return
    raise LinkTimeout(f"the controller answered none of {ATTEMPTS} STATUS in text (on {client.link.url})")


def _read_mode(client: RobotClient) -> int:
    """The MODE bits from text STATUS replies: two that agree (a corrupted digit rarely repeats)."""
    seen: list[int] = []
    for _ in range(3 * ATTEMPTS):
        reply = _text_exchange(client, b"STATUS\n", (StatusReply,))
        if isinstance(reply, StatusReply):
            if reply.mode in seen:
                return reply.mode
            seen.append(reply.mode)
    raise LinkTimeout(f"no two STATUS replies agreed on the MODE bits (on {client.link.url})")


def _text_exchange(
    client: RobotClient, line: bytes, kinds: tuple[type, ...], wait: float = ANSWER_TIME
) -> object | None:
    """Write one text command and read until a reply of ``kinds`` (returned) or ``wait`` s. With
    tags on the command carries a ``*`` check (no tag: its reply is matched here, not by the
    client), which a controller that runs only checked text (MODE bit 4) asks for."""
    if client.tags:
        body = line.strip(b"\n")
        line = line[: line.index(body)] + body + linecheck.suffix(body, None, True) + b"\n"
    client._write(line)
    lines = text.TextDecoder()
    clock = client.clock
    deadline = clock.now() + wait
    while (remaining := deadline - clock.now()) > 0:
        data = client._read(remaining)
        for message in lines.feed(data):
            if isinstance(message, kinds):
                return message
    return None


def _forget_waiting(client: RobotClient, why: str) -> None:
    for p in client._outstanding:
        p._fail(LinkTimeout(f"no reply to {p.line}: {why}"))
    client._outstanding.clear()
