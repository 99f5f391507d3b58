"""Path files: round trip, and a clear error naming the line and column for every malformed input."""

from __future__ import annotations

import io
import math
from pathlib import Path as FsPath

import numpy as np
import pytest

from omnibot.control.paths import Path, PathFileError, format_path, parse_path, read_path, write_path


def test_round_trip_with_and_without_speed(tmp_path: FsPath) -> None:
    path = Path(
        np.array([0.0, 0.5, 1.0]),
        np.array([0.0, 0.1, 0.0]),
        np.array([0.0, 0.2, -0.1]),
        np.array([0.0, 1.0, 2.0]),
        np.array([0.0, 0.5, 0.0]),
    )
    target = tmp_path / "p.csv"
    write_path(path, target)
    assert target.read_text().startswith("t,x,y,theta,v\n")
    back = read_path(target)
    for col in ("x", "y", "theta", "t", "v"):
        np.testing.assert_allclose(getattr(back, col), getattr(path, col), atol=1e-6)
    no_speed = parse_path(format_path(path.without_speed()))
    assert no_speed.v is None


def test_columns_in_any_order_comments_and_blank_lines() -> None:
    text = "# taught on the lab floor\ntheta,y,x,t\n\n0,0,0,0\n0.5,0.2,1,1\n"
    p = parse_path(text)
    assert p.x.tolist() == [0.0, 1.0] and p.y.tolist() == [0.0, 0.2] and p.theta.tolist() == [0.0, 0.5]
    assert p.length == pytest.approx(math.hypot(1.0, 0.2))


def test_x_y_alone_is_a_path_facing_its_tangent_timed_by_the_profile() -> None:
    p = parse_path("x,y\n0,0\n1,0\n1,1\n0,1\n")
    assert p.t is None and p.v is None
    np.testing.assert_allclose(p.theta, [0.0, math.pi / 4, 3 * math.pi / 4, math.pi])
    assert parse_path("t,x,y\n0,0,0\n1,0,1\n").theta.tolist() == pytest.approx([math.pi / 2] * 2)
    assert parse_path("x,y,theta\n0,0,0.3\n1,0,0.3\n").t is None


def test_heading_is_unwrapped() -> None:
    p = parse_path("t,x,y,theta\n0,0,0,3.1\n1,1,0,-3.1\n")
    assert p.theta[1] == pytest.approx(2 * math.pi - 3.1)


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("", "empty file; expected the header t,x,y,theta[,v]"),
        ("t,x,theta\n0,0,0\n1,1,1\n", "line 1: missing column(s) y"),
        ("t,x,y,thetta\n", "line 1: unknown column 'thetta'; did you mean 'theta'?"),
        ("t,x,y,theta,x\n", "line 1: column 'x' appears twice"),
        ("t,x,y,theta\n0,0,0,0\n1,1,abc,0\n", "line 3, column y: 'abc' is not a number"),
        ("t,x,y,theta\n0,0,0,0\n1,1,0\n", "line 3: expected 4 fields (t,x,y,theta), got 3"),
        ("t,x,y,theta\n0,0,0,0\n1,nan,0,0\n", "line 3, column x: 'nan' is not finite"),
        ("t,x,y,theta\n0,0,0,0\n1,1e300,0,0\n", "line 3, column x: 1e300 is out of range (at most 10000 m)"),
        ("t,x,y,theta\n0,0,0,0\n1,0,-10001,0\n", "line 3, column y: -10001 is out of range"),
        (
            "t,x,y,theta\n0,0,0,0\n1,0,0,1e9\n",
            "line 3, column theta: 1e9 is out of range (at most 10000 rad)",
        ),
        ("t,x,y,theta\n0,0,0,0\n1e7,1,0,0\n", "line 3, column t: 1e7 is out of range"),
        (
            "t,x,y,theta,v\n0,0,0,0,1e5\n1,1,0,0,1\n",
            "line 2, column v: 1e5 is out of range (at most 100 m/s)",
        ),
        ("t,x,y,theta\n1,0,0,0\n0.5,1,0,0\n", "line 3, column t: time 0.5 is before the previous row's 1"),
        ("t,x,y,theta,v\n0,0,0,0,0\n1,1,0,0,-2\n", "line 3, column v: speed -2 is negative"),
        ("t,x,y,theta\n0,0,0,0\n", "a path needs at least two rows after the header (line 1), got 1"),
    ],
)
def test_malformed_files_name_line_and_column(text: str, message: str) -> None:
    with pytest.raises(PathFileError) as err:
        parse_path(text, "taught.csv")
    assert str(err.value).startswith(f"taught.csv: {message}")


def test_unreadable_file_and_stream(tmp_path: FsPath) -> None:
    with pytest.raises(PathFileError, match="cannot read"):
        read_path(tmp_path / "missing.csv")
    (tmp_path / "bin.csv").write_bytes(b"\xff\xfe\x00")
    with pytest.raises(PathFileError, match="not a text"):
        read_path(tmp_path / "bin.csv")
    stream = io.StringIO("t,x,y,theta\n0,0,0,0\n1,1,0,0\n")
    assert len(read_path(stream, "stdin")) == 2
    with pytest.raises(PathFileError, match="cannot write"):
        write_path(parse_path("t,x,y,theta\n0,0,0,0\n1,1,0,0\n"), tmp_path / "no" / "dir.csv")


def test_a_spreadsheets_csv_utf8_with_a_byte_order_mark(tmp_path: FsPath) -> None:
    """A spreadsheet's "CSV UTF-8" starts with a byte order mark and ends lines with CRLF."""
    file = tmp_path / "from spreadsheet.csv"
    file.write_bytes(b"\xef\xbb\xbft,x,y,theta\r\n0,0,0,0\r\n1,0.5,0,0\r\n")
    path = read_path(file)
    assert path.x.tolist() == [0.0, 0.5]
    assert path.t is not None and path.t.tolist() == [0.0, 1.0]
