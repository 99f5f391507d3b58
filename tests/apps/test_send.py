"""``omnibot send`` on sim://, called through ``main(argv)``."""

from __future__ import annotations

from pathlib import Path

import pytest

from omnibot.cli import main
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


def test_send_through_a_spy_link(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    trace = tmp_path / "trace.txt"
    assert main(["send", "STATUS", "--port", f"spy+sim://omni4?file={trace}"]) == 0
    assert "<- STATUS,1,0,16,48;" in capsys.readouterr().out
    assert "STATUS" in trace.read_text()
