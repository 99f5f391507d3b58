"""``omnibot ros2``'s bad input: one line, non-zero, before any robot or DDS is touched."""

from __future__ import annotations

import sys

import pytest

from omnibot.cli import main


@pytest.mark.parametrize(
    ("args", "words"),
    [
        (["--namespace", "1robot"], "not a valid ROS namespace"),
        (["--namespace", "a//b"], "not a valid ROS namespace"),
        (["--cmd-vel-timeout", "0"], "--cmd-vel-timeout"),
        (["--cmd-vel-timeout", "nan"], "--cmd-vel-timeout"),
        (["--duration", "-1"], "--duration"),
    ],
)
def test_bad_options_are_refused(args: list[str], words: str, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["ros2", "--port", "sim://omni4", *args]) != 0
    err = capsys.readouterr().err
    assert words in err and "Traceback" not in err


def test_without_cyclonedds_it_says_how_to_install(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    for name in [
        m for m in sys.modules if m == "cyclonedds" or m.startswith(("cyclonedds.", "omnibot.ros2."))
    ]:
        monkeypatch.delitem(sys.modules, name)
    monkeypatch.setitem(sys.modules, "cyclonedds", None)  # import fails as if not installed
    assert main(["ros2", "--port", "sim://omni4", "--duration", "1"]) != 0
    err = capsys.readouterr().err
    assert "pip install 'omnibot[ros2]'" in err and "Traceback" not in err
