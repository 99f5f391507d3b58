"""Without the AVR tools the UNO parts say what is missing and how to get it, in one line."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from omnibot.uno import emulator
from omnibot.uno.emulator import UnoEmulator, UnoError, missing_tools


def test_missing_compiler_is_named_with_the_make_target(monkeypatch: pytest.MonkeyPatch) -> None:
    real = shutil.which
    monkeypatch.setattr(shutil, "which", lambda tool: None if tool == "avr-g++" else real(tool))
    reason = missing_tools()
    assert reason is not None and "avr-g++" in reason and "make avr-tools" in reason
    with pytest.raises(UnoError, match="make avr-tools"):
        UnoEmulator("omni4")


def test_missing_simavr_headers_are_named(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    monkeypatch.setattr(emulator, "SIMAVR_HEADER", tmp_path / "absent.h")
    reason = missing_tools()
    assert reason is not None and "libsimavr-dev" in reason


def test_robot_without_uno_firmware_is_named(monkeypatch: pytest.MonkeyPatch) -> None:
    if missing_tools():
        pytest.skip(f"emulated UNO: {missing_tools()}")
    with pytest.raises(
        UnoError, match=r"no UNO firmware for robot 'omni3': it is generated for mecanum4, omni4"
    ):
        emulator.build("omni3")
    with pytest.raises(UnoError, match=r"no Mega firmware for robot 'omni3'"):
        emulator.build("omni3", "mega")
    with pytest.raises(UnoError, match=r"no board 'due': the firmware is built for uno, mega"):
        emulator.build("omni4", "due")


def test_failed_build_reports_makes_last_lines(monkeypatch: pytest.MonkeyPatch) -> None:
    if missing_tools():
        pytest.skip(f"emulated UNO: {missing_tools()}")
    with pytest.raises(UnoError, match=r"make .* no-such-target failed: .*No rule to make target"):
        emulator._make("-C", str(emulator.FIRMWARE_DIR), "no-such-target")


def test_cli_error_is_one_line(monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]) -> None:
    monkeypatch.setattr(emulator, "SIMAVR_HEADER", Path("/nonexistent/sim_avr.h"))
    assert emulator.main(["omni4"]) == 1
    err = capsys.readouterr().err
    assert err.startswith("error: ") and err.count("\n") == 1
