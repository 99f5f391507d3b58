r"""Text codec of the line protocol (docs/protocol.md): messages <-> ASCII lines, no I/O.

Layout::

    command, host -> controller (at most 64 bytes before the terminator):
        KEYWORD[,p1[,p2[,p3[,p4[,p5]]]]]  ( ";" | CR | LF )+        e.g.  MOVE,2,40,0,0\n
        keyword case-insensitive, pi signed decimal 16-bit, spaces around fields ignored
    reply or event, controller -> host (at most 256 bytes before CR LF):
        KEYWORD[,field...]  CR LF                                   e.g.  ERROR,23,unknown command\r\n
        STATUS,<state>,<queued>,<capacity>,<mode>;POWER,<p1>..<pn>;MOVE,<L>,<V>,<D>,<C>  CR LF
        (";" is part of a reply line; only CR and LF end one)

    either may end with the project's suffix ``#tag*check`` (protocol/linecheck.py): a command's
    tag (1..4 digits) comes back on its reply; check = CRC-16 of the line before "*", 4 hex digits

``decode(buf)`` reads replies and events (the host's direction), ``decode_command(buf)`` commands;
both return ``(bytes used, message or None)`` and never raise on bad input: a bad line comes back as
:class:`Malformed` (a line whose check does not match too). ``decode_tagged`` also returns a reply's
tag. :class:`TextDecoder` keeps the buffer for a byte stream.
"""

from __future__ import annotations

import re
from collections.abc import Iterator
from typing import Final

from omnibot.errors import ProtocolError
from omnibot.protocol import codes, linecheck
from omnibot.protocol.messages import (
    COMMAND_BY_KEYWORD,
    Ack,
    Command,
    ErrorReply,
    HelloReply,
    Idle,
    Malformed,
    Message,
    Ok,
    Range,
    StatusReply,
    Telemetry,
    Warn,
    check_command,
    is_command,
)

_COMMAND_END_RE: Final = re.compile(rb"[;\r\n]")
_LINE_END_RE: Final = re.compile(rb"[\r\n]")
_INT_RE: Final = re.compile(r"[+-]?[0-9]+\Z")
_INF_RE: Final = re.compile(r"[+-]?inf\Z", re.IGNORECASE)
_PLAIN_INTS_RE: Final = re.compile(r" *[+-]?[0-9]+ *(?:, *[+-]?[0-9]+ *)*\Z")  # spaces only: the rest slowly
_SPACES: Final = " \t"  # what may surround a command's keyword or parameter (not VT, FF, ...)
TAG_MAX: Final = 10**linecheck.TAG_DIGITS - 1
"""The largest tag (tags are 0..9999; the client uses 1..9999, 0 meaning none)."""
_LABEL_BAD_RE: Final = re.compile(r"[\x00-\x1f\x7f-\U0010ffff]")

Decoded = Message | Malformed


# --- encoding ------------------------------------------------------------------------------------------
def encode(message: Message, terminator: bytes | None = None, tag: int | None = None) -> bytes:
    """One message as a line: a command ends with LF, a reply or event with CR LF (or ``terminator``).

    With ``tag`` (0..9999) the line ends with ``#tag*check`` (see protocol/linecheck.py).
    Raises ProtocolError for what the text protocol cannot carry (a parameter outside 16 bits, more
    than 5 parameters, a command over 64 bytes, a text with control characters, an ACK).
    """
    if isinstance(message, Ack):
        raise ProtocolError("ACK exists only in the binary protocol")
    if is_command(message):
        line = with_suffix(_join(message.keyword, check_command(message)).encode("ascii"), tag)
        if len(line) > codes.LINE_MAX:
            raise ProtocolError(f"{message.keyword}: command longer than {codes.LINE_MAX} bytes")
        end = codes.COMMAND_END if terminator is None else terminator
    else:
        line = with_suffix(_reply_line(message).encode("ascii"), tag)
        if len(line) > codes.EVENT_LINE_MAX:
            raise ProtocolError(f"{message.keyword}: line longer than {codes.EVENT_LINE_MAX} bytes")
        end = codes.LINE_END if terminator is None else terminator
    return line + end


def with_suffix(line: bytes, tag: int | None) -> bytes:
    """``line`` with ``#tag*check`` appended (``line`` itself if ``tag`` is None)."""
    if tag is None:
        return line
    if not 0 <= tag <= TAG_MAX:
        raise ProtocolError(f"tag {tag} outside 0..{TAG_MAX}")
    return line + linecheck.suffix(line, str(tag).encode(), True)


def split_suffix(line: bytes) -> tuple[bytes, int | None, bool]:
    """(body, tag or None, check failed) of a line without its terminator."""
    end, tag_start, tag_end, checked = linecheck.split(line)
    tag = int(line[tag_start:tag_end]) if tag_start >= 0 else None
    return line[:end], tag, checked == linecheck.BAD_CHECK


def _join(keyword: str, params: tuple[int, ...]) -> str:
    return ",".join((keyword, *map(str, params)))


def _label(text: str, what: str, commas: bool = True) -> str:
    if _LABEL_BAD_RE.search(text) or (not commas and "," in text):
        raise ProtocolError(f"{what} {text!r}: printable ASCII only{'' if commas else ', no commas'}")
    return text


def _reply_line(message: Message) -> str:
    if isinstance(message, ErrorReply | Warn):
        text = _label(message.description, "text")
        return f"{message.keyword},{message.code},{text}"
    if isinstance(message, HelloReply):
        if not message.name:
            raise ProtocolError("HELLO reply needs a robot name")
        name = _label(message.name, "robot name", commas=False)
        return f"HELLO,{message.version},{name},{message.motors}"
    if isinstance(message, StatusReply):
        head = _join("STATUS", (message.state, message.queued, message.capacity, message.mode))
        return f"{head};{_join('POWER', message.powers)};{_join('MOVE', message.move)}"
    return _join(message.keyword, message.params())


# --- decoding ------------------------------------------------------------------------------------------
def decode(buf: bytes | bytearray) -> tuple[int, Decoded | None]:
    """Decode the first reply or event line in ``buf``: (bytes used, message or None).

    None with used > 0: only terminators (or a blank line) were consumed; with used == 0: more bytes
    are needed. A line longer than 256 bytes is returned as Malformed as soon as that is certain;
    the caller then drops bytes up to the next terminator (:class:`TextDecoder` does).
    """
    used, message, _ = decode_tagged(buf)
    return used, message


def decode_tagged(
    buf: bytes | bytearray, require_check: bool = False
) -> tuple[int, Decoded | None, int | None]:
    """:func:`decode` that also returns the line's tag (None: untagged). ``require_check``: a tagged
    line without its ``*`` check is damaged (a host that sends every tagged command with a check gets
    every tagged reply with one; a line end moved in front of the ``*`` cuts it off)."""
    used, line, cut = _next_line(buf, _LINE_END_RE, codes.EVENT_LINE_MAX)
    if line is None:
        return used, None, None
    if cut:
        return used, Malformed(line, "line too long"), None
    end, tag_start, tag_end, checked = linecheck.split(line)
    if checked == linecheck.BAD_CHECK:
        return used, Malformed(line, "checksum mismatch"), None
    if require_check and tag_start >= 0 and checked == linecheck.NO_CHECK:
        return used, Malformed(line, "tagged reply without its check"), None
    body, tag = line[:end], int(line[tag_start:tag_end]) if tag_start >= 0 else None
    message = parse_line(body)
    if isinstance(message, Malformed):
        return used, Malformed(line, message.reason), None
    return used, message, tag


def decode_command(buf: bytes | bytearray) -> tuple[int, Command | Malformed | None]:
    """Decode the first command in ``buf`` (``;``, CR or LF end it): (bytes used, command or None).

    A bad command is Malformed with the ERROR code a controller answers (22..25, 34).
    """
    used, line, cut = _next_line(buf, _COMMAND_END_RE, codes.LINE_MAX)
    if line is None:
        return used, None
    if cut:
        return used, Malformed(line, "command too long", codes.E_TOO_LONG)
    return used, parse_command(line)


def _next_line(buf: bytes | bytearray, ends: re.Pattern[bytes], limit: int) -> tuple[int, bytes | None, bool]:
    """(used, line or None, cut): skip terminators, take one line and the terminators after it."""
    n = len(buf)
    start = 0
    while start < n and ends.match(buf, start):
        start += 1
    found = ends.search(buf, start)
    if found is None:
        if n - start > limit:
            return n, bytes(buf[start:]), True
        return start, None, False
    end = used = found.start()
    while used < n and ends.match(buf, used):
        used += 1
    return used, bytes(buf[start:end]), False


def _ints(fields: list[str], spaces: str | None = None, inf_at: int = -1) -> list[int] | None:
    """The fields as integers (``INF`` tokens too at index ``inf_at``), None if one is not."""
    if spaces is None and inf_at < 0 and _plain_ints(fields):
        return [int(f) for f in fields]  # a TEL line's twenty fields without a regex each
    out = []
    for i, f in enumerate(fields):
        token = f.strip(spaces)
        if i == inf_at and _INF_RE.match(token):
            out.append(-codes.INF if token[0] == "-" else codes.INF)
        elif _INT_RE.match(token):
            out.append(int(token))
        else:
            return None
    return out


def _plain_ints(fields: list[str]) -> bool:
    """Whether every field is optional whitespace, an optional sign and ASCII digits (what
    :data:`_INT_RE` takes once stripped), told by one pass over them all."""
    return _PLAIN_INTS_RE.match(",".join(fields)) is not None


def parse_command(line: bytes) -> Command | Malformed | None:
    """One command without its terminator; None for a blank one. A ``#tag*check`` suffix is split
    off (and checked: ERROR 26 if it does not match), as the controller does.

    Checks, in order: length (22), check (41), keyword (23), at most 5 parameters (VEL 7; 24), integers
    (25), 16-bit range (34), the command's parameter count (24). Only spaces and tabs surround
    fields; ``INF``/``-INF`` (any case) is 30000/-30000 where codes.INF_PARAMS allows it. Limits of
    the robot are the controller's business.
    """
    if len(line) > codes.LINE_MAX:
        return Malformed(line, "command too long", codes.E_TOO_LONG)
    body, _, bad = split_suffix(line)
    if bad:
        return Malformed(line, "checksum mismatch", codes.E_CHECKSUM)
    fields = body.decode("latin-1").split(",")
    keyword = fields[0].strip(_SPACES).upper()
    if not keyword and len(fields) == 1:
        return None
    cls = COMMAND_BY_KEYWORD.get(keyword)
    if cls is None:
        return Malformed(line, "unknown command", codes.E_UNKNOWN)
    if len(fields) - 1 > codes.params_max(cls.TYPE):
        return Malformed(line, "wrong number of parameters", codes.E_PARAM_COUNT)
    params = _ints(fields[1:], _SPACES, codes.INF_PARAMS.get(cls.TYPE, -1))
    if params is None:
        return Malformed(line, "parameter is not an integer", codes.E_NOT_INTEGER)
    if any(not codes.INT_MIN <= p <= codes.INT_MAX for p in params):
        return Malformed(line, "value outside 16-bit range", codes.E_RANGE16)
    try:
        return cls.from_params(params)
    except ProtocolError:
        return Malformed(line, "wrong number of parameters", codes.E_PARAM_COUNT)


_SIMPLE: Final[dict[str, type[Ok | Idle | Range | Telemetry]]] = {
    "OK": Ok,
    "IDLE": Idle,
    "RANGE": Range,
    "TEL": Telemetry,
}


def parse_line(line: bytes) -> Decoded | None:
    """One reply or event line without CR LF; None for a blank one, Malformed for anything bad."""
    try:
        text = line.decode("ascii")
    except UnicodeDecodeError:
        return Malformed(line, "not ASCII")
    if len(line) > codes.EVENT_LINE_MAX:
        return Malformed(line, "line too long")
    head, comma, rest = text.partition(",")
    keyword = head.strip().upper()
    if not keyword and not comma:
        return None
    try:
        if keyword in _SIMPLE:
            params = _ints(rest.split(",")) if comma else []
            if params is None:
                return Malformed(line, "field is not an integer")
            return _SIMPLE[keyword].from_params(params)
        if keyword in ("ERROR", "WARN"):
            code_field, _, label = rest.partition(",")
            code = _ints([code_field])
            if not comma or code is None:
                return Malformed(line, "code is not an integer")
            return (ErrorReply if keyword == "ERROR" else Warn)(code[0], label)
        if keyword == "HELLO":
            return _parse_hello(line, rest.split(",") if comma else [])
        if keyword == "STATUS":
            return _parse_status(line, text)
    except ProtocolError as exc:
        return Malformed(line, str(exc))
    return Malformed(line, "unknown keyword")


def _parse_hello(line: bytes, fields: list[str]) -> Decoded:
    numbers = _ints([fields[0], fields[-1]]) if len(fields) >= 3 else None
    name = ",".join(fields[1:-1]).strip()
    if numbers is None or not name:
        return Malformed(line, "HELLO needs <version>,<robot name>,<motors>")
    return HelloReply(numbers[0], name, numbers[1])


def _parse_status(line: bytes, text: str) -> Decoded:
    parts = text.split(";")
    sections = [p.split(",") for p in parts]
    if len(parts) != 3 or [s[0].strip().upper() for s in sections] != ["STATUS", "POWER", "MOVE"]:
        return Malformed(line, "STATUS needs STATUS,...;POWER,...;MOVE,...")
    head, powers, move = (_ints(s[1:]) for s in sections)
    if head is None or powers is None or move is None or len(head) != 4 or len(move) != 4:
        return Malformed(line, "STATUS: bad fields")
    return StatusReply(
        head[0], head[1], head[2], head[3], tuple(powers), (move[0], move[1], move[2], move[3])
    )


# --- stream decoder --------------------------------------------------------------------------------------
class TextDecoder:
    """Feed bytes, get messages: ``for msg in dec.feed(chunk): ...``.

    ``commands=True`` decodes commands (the controller's direction) instead of replies and events.
    Messages are decoded lazily as the iterator is consumed; stop early (e.g. at the OK of a switch
    to binary) and :meth:`rest` hands over the bytes not yet decoded.
    """

    def __init__(self, commands: bool = False, require_check: bool = False) -> None:
        self.commands = commands
        self.require_check = require_check
        """Replies: a tagged line without its check is Malformed (see :func:`decode_tagged`)."""
        self._buf = bytearray()
        self._skipping = False
        self._ends = _COMMAND_END_RE if commands else _LINE_END_RE
        self.ends = b";\r\n" if commands else b"\r\n"
        """The bytes :attr:`_ends` matches: a message is decoded once one of them comes (or :meth:`room` runs out)."""
        self._limit = codes.LINE_MAX if commands else codes.EVENT_LINE_MAX
        self._open = True
        """The buffer holds no terminator and no line is being skipped (a drain ran to its end): bytes
        without one only lengthen its line, and a line no longer than the limit decodes to nothing yet."""

    def feed(self, data: bytes) -> Iterator[Decoded]:
        """Append ``data``; iterate over the messages now complete."""
        return (message for message, _ in self.feed_tagged(data))

    def feed_tagged(self, data: bytes) -> Iterator[tuple[Decoded, int | None]]:
        """:meth:`feed` with each message's tag (None: untagged; always None for commands)."""
        self._buf.extend(data)
        if self._open and len(self._buf) <= self._limit and not self._ends.search(data):
            return iter(())  # a line still arriving (most reads of a paced link): nothing to decode
        self._open = False
        return self._drain()

    def _drain(self) -> Iterator[tuple[Decoded, int | None]]:
        while True:
            if self._skipping:
                found = self._ends.search(self._buf)
                if found is None:
                    self._buf.clear()  # still skipping: not open (bytes without a terminator are dropped)
                    return
                del self._buf[: found.start()]
                self._skipping = False
            tag = None
            message: Decoded | None
            if self.commands:
                used, message = decode_command(self._buf)
            else:
                used, message, tag = decode_tagged(self._buf, self.require_check)
            if used == 0:
                self._open = True
                return
            cut = isinstance(message, Malformed) and self._ends.search(self._buf, 0, used) is None
            del self._buf[:used]
            self._skipping = cut
            if message is not None:
                yield message, tag

    def room(self) -> int:
        """Bytes that may still come without one of :attr:`ends` before the line is too long (and is
        decoded, Malformed, at the next feed)."""
        return self._limit - len(self._buf)

    def rest(self) -> bytes:
        """Take the bytes not decoded yet (e.g. the first binary frames after a MODE switch)."""
        out = bytes(self._buf)
        self._buf.clear()
        self._skipping = False
        self._open = True
        return out
