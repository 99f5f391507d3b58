"""``omnibot console`` on sim://, called through ``main(argv)``."""

from __future__ import annotations

import argparse
import io
from collections.abc import Iterator
from pathlib import Path

import pytest

from omnibot.apps.console import run_console
from omnibot.cli import main
from omnibot.protocol import codes

PIPED = """\
STATUS
:tel off
TELEM,50,1
:wait 0.2
:tel on
TELEM,0,0
SONAR,1,60,0,300,0
MOVE,10,40,0,0
:idle 2
FOO

:status
:binary
STATUS
:text
:wait x
:tel sideways
:help
:quit
STATUS
"""


def test_console_piped(monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]) -> None:
    monkeypatch.setattr("sys.stdin", io.StringIO(PIPED))
    assert main(["console", "--port", "sim://omni4?world=room"]) == 0
    out = capsys.readouterr().out
    lines = out.splitlines()
    # the power-up greeting is read while the link settles, so the first reply is STATUS's own
    assert lines[:2] == ["-> STATUS", "<- STATUS,1,0,16,48;POWER,0,0,0,0;MOVE,0,0,0,0"]
    assert not any(line.startswith("<- TEL") for line in lines[: lines.index("-> :tel on")])
    assert any(line.startswith("<- RANGE sonar 1: ") and line.endswith(" cm") for line in lines)
    assert "<- IDLE" in lines and "idle" in lines
    assert "<- ERROR,23,unknown command" in lines
    assert any(line.startswith("idle, 0/16 queued, mode 48") for line in lines)  # checked, sequenced text
    assert f"binary protocol, version {codes.VERSIONS[-1]}" in lines and "text protocol" in lines
    assert any(line.startswith("<- STATUS,1,0,16,52;") for line in lines)
    assert "!! expected seconds, got 'x'" in lines
    assert any(line.startswith("?? unknown console command") for line in lines)
    assert ":quit" in out and lines[-1] == "-> :quit"


def test_console_interactive(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    monkeypatch.setenv("HOME", str(tmp_path))
    typed = iter(["STATUS", "TELEM,100,64", ":wait 0.25", "", ":tel off", "STOP"])

    def fake_input(prompt: str) -> str:
        assert prompt == "> "
        try:
            return next(typed)
        except StopIteration:
            raise EOFError from None

    out = io.StringIO()
    args = argparse.Namespace(port="sim://omni4", timeout=2.0)
    assert run_console(args, out=out, interactive=True, input_fn=fake_input) == 0
    lines = out.getvalue().splitlines()
    assert lines[0].startswith("omnibot console on sim://omni4")
    assert "<- STATUS,1,0,16,48;POWER,0,0,0,0;MOVE,0,0,0,0" in lines
    assert any(line.startswith("<- TEL ") and line.endswith("idle q0") for line in lines)
    assert lines[-1] == "<- OK"
    assert (tmp_path / ".omnibot_history").exists()


@pytest.fixture(autouse=True)
def _no_history_leak(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> Iterator[None]:
    monkeypatch.setenv("HOME", str(tmp_path))
    yield
