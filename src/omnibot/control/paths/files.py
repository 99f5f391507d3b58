"""Path files: CSV with the header ``t,x,y,theta`` and an optional ``v`` column; ``x,y`` alone is a path too.

Units: t in s, x and y in m, theta in rad (the body heading to hold), v in m/s (the speed to drive
at that point, e.g. as taught). Only ``x`` and ``y`` are required: without ``theta`` the body faces
the path's tangent (the direction of travel, :func:`~omnibot.control.paths.path.tangent_headings`),
without ``t`` the times come from the speed profile the follower plans (as they do anyway: ``t`` is
kept, not driven by). Columns may come in any order; blank lines and lines starting with
``#`` are skipped. Rules: the header names each column once, no unknown columns; every row has one
field per column, each a finite number within :data:`LIMITS` (a robot's path, not a typo of
exponent: ``1e300`` would make the speed profile take gigabytes); t never decreases; v is not
negative; at least two rows.
A broken file raises :class:`PathFileError`, which names the file, the line and the column::

    path.csv: line 7, column theta: 'abc' is not a number
"""

from __future__ import annotations

import csv
import difflib
import io
import math
from pathlib import Path as FsPath
from typing import IO

import numpy as np

from omnibot.control.paths.path import Path, tangent_headings
from omnibot.errors import ConfigError

REQUIRED = ("x", "y")
OPTIONAL = ("t", "theta", "v")
HEADER = "t,x,y,theta[,v] (or x,y: the heading from the path's tangent)"
LIMITS = {"t": (1e6, "s"), "x": (1e4, "m"), "y": (1e4, "m"), "theta": (1e4, "rad"), "v": (100.0, "m/s")}
"""Largest magnitude of each column: 10 km, 10,000 rad (1,600 turns), 11 days, 100 m/s."""


class PathFileError(ConfigError):
    """A path file that cannot be read; the message names the line and column."""


def read_path(source: str | FsPath | IO[str], name: str | None = None) -> Path:
    """Read a path file (a file name or an open text stream)."""
    if isinstance(source, str | FsPath):
        label = name or str(source)
        try:
            # utf-8-sig: a spreadsheet's "CSV UTF-8" starts with a byte order mark
            with open(source, encoding="utf-8-sig", newline="") as f:
                return _parse(f, label)
        except OSError as exc:
            raise PathFileError(f"{label}: cannot read: {exc.strerror or exc}") from None
        except UnicodeDecodeError:
            raise PathFileError(f"{label}: not a text (UTF-8) file") from None
    return _parse(source, name or str(getattr(source, "name", "<stream>")))


def parse_path(text: str, name: str = "<text>") -> Path:
    """Parse path CSV text."""
    return _parse(io.StringIO(text), name)


def _parse(stream: IO[str], label: str) -> Path:
    reader = csv.reader(stream)
    header: list[str] | None = None
    header_line = 0
    columns: dict[str, list[float]] = {}
    for row in reader:
        line = reader.line_num
        if not row or all(not c.strip() for c in row) or row[0].lstrip().startswith("#"):
            continue
        if header is None:
            header, header_line = [c.strip().lower() for c in row], line
            _check_header(header, label, line)
            columns = {h: [] for h in header}
            continue
        if len(row) != len(header):
            raise PathFileError(
                f"{label}: line {line}: expected {len(header)} fields ({','.join(header)}), got {len(row)}"
            )
        for col, text in zip(header, row, strict=True):
            try:
                value = float(text)
            except ValueError:
                raise PathFileError(
                    f"{label}: line {line}, column {col}: {text.strip()!r} is not a number"
                ) from None
            if not math.isfinite(value):
                raise PathFileError(f"{label}: line {line}, column {col}: {text.strip()!r} is not finite")
            bound, unit = LIMITS[col]
            if abs(value) > bound:
                raise PathFileError(
                    f"{label}: line {line}, column {col}: {text.strip()} is out of range (at most {bound:g} {unit})"
                )
            if col == "v" and value < 0:
                raise PathFileError(f"{label}: line {line}, column v: speed {value:g} is negative")
            values = columns[col]
            if col == "t" and values and value < values[-1]:
                raise PathFileError(
                    f"{label}: line {line}, column t: time {value:g} is before the previous row's {values[-1]:g}"
                )
            values.append(value)
    if header is None:
        raise PathFileError(f"{label}: empty file; expected the header {HEADER}")
    rows = len(columns["x"])
    if rows < 2:
        raise PathFileError(
            f"{label}: a path needs at least two rows after the header (line {header_line}), got {rows}"
        )
    arr = {k: np.array(v, dtype=float) for k, v in columns.items()}
    theta = arr["theta"] if "theta" in arr else tangent_headings(arr["x"], arr["y"])
    return Path(arr["x"], arr["y"], theta, arr.get("t"), arr.get("v"))


def _check_header(header: list[str], label: str, line: int) -> None:
    known = ("t", "x", "y", "theta", "v")
    for h in header:
        if h not in known:
            close = difflib.get_close_matches(h, known, n=1, cutoff=0.5)
            hint = f"; did you mean '{close[0]}'?" if close else f"; the columns are {','.join(known)}"
            raise PathFileError(f"{label}: line {line}: unknown column '{h}'{hint}")
    for h in known:
        if header.count(h) > 1:
            raise PathFileError(f"{label}: line {line}: column '{h}' appears twice")
    missing = [h for h in REQUIRED if h not in header]
    if missing:
        raise PathFileError(
            f"{label}: line {line}: missing column(s) {','.join(missing)}; the header must be {HEADER}"
        )


def format_path(path: Path) -> str:
    """The CSV text of a path. Without times, t is the arc length (a nominal 1 m/s)."""
    t = path.t if path.t is not None else path.s
    out = io.StringIO()
    out.write("t,x,y,theta" + (",v" if path.v is not None else "") + "\n")
    for i in range(len(path)):
        row = f"{t[i]:.4f},{path.x[i]:.6f},{path.y[i]:.6f},{path.theta[i]:.6f}"
        if path.v is not None:
            row += f",{path.v[i]:.4f}"
        out.write(row + "\n")
    return out.getvalue()


def write_path(path: Path, target: str | FsPath | IO[str]) -> None:
    """Write a path file (a file name or an open text stream)."""
    text = format_path(path)
    if isinstance(target, str | FsPath):
        try:
            FsPath(target).write_text(text, encoding="utf-8")
        except OSError as exc:
            raise PathFileError(f"{target}: cannot write: {exc.strerror or exc}") from None
    else:
        target.write(text)
