"""Progress on a terminal, none off one: the bars and notices of the long commands (stderr)."""

from __future__ import annotations

import io
import sys
from pathlib import Path

import pytest

from omnibot.cli import main
from omnibot.progress import notice, progress_bar


class Terminal(io.StringIO):
    """A standard error that is a terminal."""

    def isatty(self) -> bool:
        return True


class Pipe(io.StringIO):
    def isatty(self) -> bool:
        return False


@pytest.mark.parametrize(("stream", "shown"), [(Terminal, True), (Pipe, False)])
def test_bars_and_notices_only_on_a_terminal(
    monkeypatch: pytest.MonkeyPatch, stream: type[io.StringIO], shown: bool
) -> None:
    err = stream()
    monkeypatch.setattr(sys, "stderr", err)
    notice("waiting for the controller")
    with progress_bar("demo", 5, unit="example") as bar:
        bar.update(5)
    text = err.getvalue()
    assert ("omnibot: waiting for the controller\n" in text) is shown
    assert ("demo: 100%" in text and "5/5" in text) is shown
    assert shown or text == ""


def test_follow_shows_the_metres_covered_on_a_terminal(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "line.csv"
    path.write_text("t,x,y,theta\n0,0,0,0\n1,0.25,0,0\n2,0.5,0,0\n", encoding="utf-8")
    err = Terminal()
    monkeypatch.setattr(sys, "stderr", err)
    assert main(["follow", str(path)]) == 0
    text = err.getvalue()
    assert "follow line.csv:" in text and "/0.50 m" in text
    assert capsys.readouterr().out.startswith("omnibot follow: omni4")  # the report stays on stdout
