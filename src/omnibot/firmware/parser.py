"""Text protocol input: split the byte stream into commands and parse one command.

``;``, CR and LF terminate a command; a run of them counts as one and empty commands are ignored.
A command longer than ``line_max`` bytes is reported once (``None`` in the output list, which the
controller answers with ERROR 22) and everything up to the next terminator is dropped.
:func:`parse` reads one command's body (the controller splits off a ``#tag*check`` suffix first,
see :mod:`omnibot.protocol.linecheck`).
"""

from omnibot.protocol import codes

KEYWORDS = {}
for _name, _id in codes.COMMANDS.items():
    KEYWORDS[_name.encode()] = _id


class LineSplitter:
    """Accumulates bytes and hands out complete commands."""

    def __init__(self, line_max: int) -> None:
        self.line_max = line_max
        self._buf = bytearray()
        self._overflow = False

    def feed(self, data: bytes, out: "list[bytes | None]", ends: "list[int]") -> None:
        """Append each completed command to ``out`` (its bytes, or None for a too-long one) and the
        offset in ``data`` just after its terminator to ``ends``."""
        parts = data.replace(b"\r", b";").replace(b"\n", b";").split(b";")
        last = len(parts) - 1
        pos = 0
        for i in range(last + 1):
            part = parts[i]
            pos += len(part) + 1
            if part:
                if self._overflow:
                    pass
                elif len(self._buf) + len(part) > self.line_max:
                    self._overflow = True
                    self._buf[:] = b""
                else:
                    self._buf.extend(part)
            if i == last:
                return
            if self._overflow:
                self._overflow = False
                out.append(None)
                ends.append(pos)
            elif self._buf:
                out.append(bytes(self._buf))
                ends.append(pos)
                self._buf[:] = b""

    def reset(self) -> None:
        """Drop the partial line and any overflow."""
        self._buf[:] = b""
        self._overflow = False


SPACES = b" \t"  # what may surround a keyword or parameter (not VT, FF, CR or LF)
_INF = b"INF"


def parse(command: bytes, params: list[int]) -> int:
    """Parse ``KEYWORD[,p1,...,p5]`` (VEL up to p7) into ``params`` (cleared first).

    Returns the keyword id (> 0), 0 for a blank command, or -code for ERROR 23, 24, 25 or 34.
    Spaces and tabs are allowed around the keyword and each parameter. The whole command's syntax
    is checked before any range: every parameter an integer (25), then each inside 16 bits (34).
    ``INF``/``-INF`` (any case) is 30000/-30000 where the protocol allows it (codes.INF_PARAMS).
    """
    del params[:]
    fields = command.split(b",")
    keyword = fields[0].strip(SPACES).upper()
    if not keyword and len(fields) == 1:
        return 0
    kw = KEYWORDS.get(keyword, 0)
    if kw == 0:
        return -codes.E_UNKNOWN
    if len(fields) - 1 > codes.params_max(kw):
        return -codes.E_PARAM_COUNT
    inf_at = codes.INF_PARAMS.get(kw, -1) + 1
    for i in range(1, len(fields)):
        tok = fields[i].strip(SPACES)
        sign = tok[:1] in (b"-", b"+")
        digits = tok[1:] if sign else tok
        if i == inf_at and digits.upper() == _INF:
            params.append(-codes.INF if tok[:1] == b"-" else codes.INF)
            continue
        if not digits or not digits.isdigit():
            del params[:]
            return -codes.E_NOT_INTEGER
        params.append(int(tok))
    for value in params:
        if value < codes.INT_MIN or value > codes.INT_MAX:
            del params[:]
            return -codes.E_RANGE16
    return kw
