"""``omnibot send`` and ``omnibot console`` on sim://, called through ``main(argv)``."""

from __future__ import annotations

import argparse
import io
from collections.abc import Iterator
from pathlib import Path

import pytest

from omnibot.apps.console import format_event, run_console
from omnibot.cli import main
from omnibot.client import ErrorEvent, Hello, RangeEvent, ResetEvent, Telemetry, Unexpected, WarnEvent
from omnibot.protocol import codes
from omnibot.protocol.messages import Malformed
from omnibot.protocol.messages import Telemetry as TelMessage
from omnibot.transport import LockstepLink, register_scheme, unregister_scheme
from tests.client.fakes import Silent


def test_send_prints_replies_and_events(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["send", "MOVE,2,40,0,0;DELTA,0,0,10,0,3", "STATUS", "--wait-idle"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[:2] == ["-> MOVE,2,40,0,0", "-> DELTA,0,0,10,0,3"]
    assert out.count("<- OK") == 2
    assert "-> STATUS" in out and out[-1] == "<- IDLE"
    assert any(line.startswith("<- STATUS,0,") for line in out)


def test_send_error_reply_exits_1(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["send", "STATUS;FOO", "move,x,1,1,1", "--port", "sim://omni3"]) == 1
    out = capsys.readouterr().out
    assert "<- ERROR,23,unknown command" in out
    assert "-> move,x,1,1,1\n<- ERROR,25,parameter is not an integer" in out


def test_send_binary(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["send", "--binary", "MOVE,5,40,0,0", "STATUS", "--wait-idle"]) == 0
    out = capsys.readouterr().out
    assert "<- STATUS,0,0,16,52;" in out and "<- IDLE" in out


@pytest.mark.parametrize(
    "argv",
    [
        ["send", "MOVE,1,40,0,0\u00b5"],
        ["send", "STATUS", "--port", "sim://omni5"],
        ["send", "STATUS", "--port", "bogus://x"],
        ["send", "STATUS", "--port", "/dev/omnibot-no-such-port"],
        ["send", ""],  # nothing sent is no success (it exited 0)
        ["send", ";", " ; "],
    ],
)
def test_send_bad_input_or_link_exits_2(argv: list[str], capsys: pytest.CaptureFixture[str]) -> None:
    assert main(argv) == 2
    assert "error" in capsys.readouterr().err


def test_send_malformed_in_binary_exits_2(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["send", "--binary", "FOO"]) == 2
    assert "malformed" in capsys.readouterr().err


def test_send_no_reply_exits_2(capsys: pytest.CaptureFixture[str]) -> None:
    register_scheme("silent", lambda u: LockstepLink(Silent(), url=u.url))
    try:
        assert main(["send", "STATUS", "--port", "silent://x", "--timeout", "3"]) == 2
    finally:
        unregister_scheme("silent")
    assert "no reply to HELLO" in capsys.readouterr().err


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


def test_format_event() -> None:
    assert format_event(RangeEvent(time=0, sonar=1, distance=0.42)) == "<- RANGE sonar 1: 42 cm"
    assert format_event(RangeEvent(time=0, sonar=2, distance=None)) == "<- RANGE sonar 2: no echo"
    warn = WarnEvent(time=0, code=13, text="emergency stop by sonar")
    assert format_event(warn) == "<- WARN 13 emergency stop by sonar"
    assert "no command waiting" in format_event(ErrorEvent(time=0, code=36, text="internal fault"))
    assert (
        format_event(ResetEvent(time=0, hello=Hello(1, "omni4", 4)))
        == "<- HELLO,1,omni4,4 (controller reset)"
    )
    odd = Unexpected(time=0, message=Malformed(b"\xff", "not ASCII"), reason="not ASCII")
    assert format_event(odd) == "<- ?? not ASCII: b'\\xff'"
    tel = Telemetry.from_message(TelMessage(1504, (0, 220), (0, 912), (), 50, 100, 7190, (0, 1), (42,)), 0.0)
    assert format_event(tel) == (
        "<- TEL 1.504 s pwr 0,220 enc 0,912 gyro 0.5 deg/s hdg 1.0 deg bat 7.19 V moving q1 sonar 42cm"
    )


@pytest.fixture(autouse=True)
def _no_history_leak(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> Iterator[None]:
    monkeypatch.setenv("HOME", str(tmp_path))
    yield


def test_send_through_a_spy_link(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    trace = tmp_path / "trace.txt"
    assert main(["send", "STATUS", "--port", f"spy+sim://omni4?file={trace}"]) == 0
    assert "<- STATUS,1,0,16,48;" in capsys.readouterr().out
    assert "STATUS" in trace.read_text()
