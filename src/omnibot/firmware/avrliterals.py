"""C literals for the AVR firmware's generated headers (avrgen.py, avrfeatures.py, avrboard.py; CPython).

Strings, floats that read back exactly, lists, ``#define`` lines of protocol codes and the PROGMEM
texts of codes, calibration tables as knot rows, and the fixed-point shift of a matrix.
"""

from __future__ import annotations

import math
from collections.abc import Iterable

from omnibot.errors import ConfigError
from omnibot.protocol import codes

INT16_MAX = 32767


def c_string(text: str) -> str:
    """A C string literal of ``text``."""
    return '"' + text.replace("\\", "\\\\").replace('"', '\\"') + '"'


def c_float(value: float) -> str:
    """A C float literal that reads back as ``value`` exactly."""
    return f"{float(value)!r}f"


def c_list(values: Iterable[object]) -> str:
    """``a, b, c``: the values as they print."""
    return ", ".join(str(v) for v in values)


def c_floats(rows: Iterable[Iterable[float]]) -> str:
    """Rows of C float literals: ``{a, b}, {c, d}``."""
    return c_list("{" + c_list(c_float(v) for v in row) + "}" for row in rows)


def defines(prefix: str, keys: Iterable[str]) -> str:
    """``#define <prefix><KEY> <codes.KEY>`` for each key."""
    return "\n".join(f"#define {prefix}{key} {getattr(codes, key)}" for key in keys)


def text_defines(texts: Iterable[int]) -> str:
    """``TEXT_<code>``, the PROGMEM string of each code's text (codes.TEXTS)."""
    return "\n".join(f"static const char TEXT_{c}[] PROGMEM = {c_string(codes.TEXTS[c])};" for c in texts)


def code_texts(texts: Iterable[int]) -> str:
    """The rows of a CodeText table: ``{code, TEXT_<code>}`` for each code."""
    return ", ".join(f"{{{c}, TEXT_{c}}}" for c in texts)


def table_rows(t: list[list[float]], xscale: float, yscale: float) -> tuple[int, list[str]]:
    """A table's knots as ``{x, y}`` rows (scaled, rounded), padded to CAL_KNOTS_MAX; the count used."""
    xs, ys = t
    if len(xs) > codes.CAL_KNOTS_MAX:
        raise ConfigError(f"{len(xs)} knots, the UNO holds {codes.CAL_KNOTS_MAX}", key="calibration")
    rows = [f"{{{round(x * xscale)}, {round(y * yscale)}}}" for x, y in zip(xs, ys, strict=True)]
    rows += ["{0, 0}"] * (codes.CAL_KNOTS_MAX - len(xs))
    return len(xs), rows


def fixed_shift(rows: list[list[float]]) -> int:
    """The largest shift that keeps every value of ``rows`` times 2**shift inside int16."""
    peak = max(abs(v) for row in rows for v in row) or 1.0
    return max(0, min(14, math.floor(math.log2(INT16_MAX / peak))))
