"""Smoke test of the Foxglove live cost benchmark: its quick run delivers every message at 1 kHz."""

from __future__ import annotations

import pytest

from benchmarks import foxglove_live


def test_quick_run_delivers_every_message(capsys: pytest.CaptureFixture[str]) -> None:
    assert foxglove_live.main(["--quick"]) == 0
    rows = [line.split("|")[1:-1] for line in capsys.readouterr().out.splitlines()[2:]]
    assert [r[0].strip() for r in rows] == [
        "1,000 messages/s, one client subscribed",
        "10,000 messages/s, one client subscribed",
        "1,000 messages/s, no client",
    ]
    assert rows[0][2].strip() == "2000"  # received, at the recorder's rate
    assert all(r[3].strip().endswith("us") for r in rows)


def test_too_few_messages_is_refused(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit):
        foxglove_live.main(["--messages", "10"])
    assert "at least 100" in capsys.readouterr().err
