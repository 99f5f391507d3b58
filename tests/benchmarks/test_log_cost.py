"""The recording-cost benchmark runs (3 s each way through the pty emulator) and loses nothing."""

from __future__ import annotations

import pytest

from benchmarks import log_cost


def test_quick_run_loses_no_message(capsys: pytest.CaptureFixture[str]) -> None:
    assert log_cost.main(["--quick"]) == 0
    out = capsys.readouterr().out
    assert "lost: 0 TEL, 0 VEL, 0 unwritable" in out and "kB/s" in out
