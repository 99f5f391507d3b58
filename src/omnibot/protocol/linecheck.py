"""Tag and checksum suffix of text lines (docs/protocol.md, "Tags and checksums"; MicroPython-safe).

A project extension of the text protocol, in the manner of NMEA 0183's ``*hh``::

    line    := body [ "#" tag ] [ "*" check ]
    tag     := 1..4 decimal digits, echoed by the controller in the reply to that command
    check   := 4 hex digits: CRC-16/CCITT-FALSE of every byte of the line before the "*"

A command without ``#`` and ``*`` is today's command and gets today's reply. The controller's
reply to a command carries the command's tag (if it had one) and a check (if it had one).

Used by the firmware (parser, controller) and the host codec (protocol/text.py), so both sides
split and build suffixes the same way.
"""

HASH = 35  # "#"
STAR = 42  # "*"
TAG_DIGITS = 4  # a tag is 1..4 digits (0..9999)
CHECK_DIGITS = 4
POLY = 0x1021
INIT = 0xFFFF
CHECK = 0x29B1  # crc16(b"123456789"), CRC-16/CCITT-FALSE's check value

NO_CHECK = 0  # the line had no "*" suffix
CHECKED = 1  # it had one and it matched
BAD_CHECK = -1  # it had one and it did not match (the line must be dropped or refused)


def crc16_bitwise(data: bytes, crc: int = INIT) -> int:
    """CRC-16/CCITT-FALSE of ``data`` (poly 0x1021, init 0xFFFF, no reflection, no final XOR)."""
    for byte in data:
        crc ^= byte << 8
        for _ in range(8):
            crc = ((crc << 1) ^ POLY) & 0xFFFF if crc & 0x8000 else (crc << 1) & 0xFFFF
    return crc


try:
    from binascii import crc_hqx as _crc_hqx  # type: ignore[attr-defined,unused-ignore]

    def crc16(data: bytes, crc: int = INIT) -> int:
        """CRC-16/CCITT-FALSE of ``data``."""
        return int(_crc_hqx(data, crc))

except ImportError:  # MicroPython has no crc_hqx
    crc16 = crc16_bitwise


def _is_hex(c: int) -> bool:
    return 48 <= c <= 57 or 65 <= c <= 70 or 97 <= c <= 102


def split(line: bytes) -> "tuple[int, int, int, int]":
    """Find the suffix of ``line``: ``(body_end, tag_start, tag_end, checked)``.

    ``line[:body_end]`` is the body and ``line[tag_start:tag_end]`` the tag (none if ``tag_start``
    < 0); ``checked`` is NO_CHECK, CHECKED or BAD_CHECK. A ``*`` not followed by exactly 4 hex digits up to the end, or a
    ``#`` not followed by 1..4 digits up to the check, is no suffix: it stays in the body (where no
    keyword or integer can contain it, so the command is refused).
    """
    n = len(line)
    end = n
    checked = NO_CHECK
    if n > CHECK_DIGITS and line[n - CHECK_DIGITS - 1] == STAR:
        hexed = True
        for i in range(n - CHECK_DIGITS, n):
            if not _is_hex(line[i]):
                hexed = False
        if hexed:
            end = n - CHECK_DIGITS - 1
            if crc16(line[:end]) == int(line[end + 1 :], 16):
                checked = CHECKED
            else:
                return end, -1, -1, BAD_CHECK
    i = end
    while i > 0 and end - i <= TAG_DIGITS and 48 <= line[i - 1] <= 57:
        i -= 1
    if i > 0 and line[i - 1] == HASH and 1 <= end - i <= TAG_DIGITS:
        return i - 1, i, end, checked
    return end, -1, -1, checked


def suffix(line: bytes, tag: "bytes | None", check: bool) -> bytes:
    """The suffix to append to ``line``: ``#tag`` (if ``tag``) then ``*XXXX`` (if ``check``)."""
    out = b"" if tag is None else b"#" + tag
    if check:
        out += b"*%04X" % crc16(line + out)
    return out
