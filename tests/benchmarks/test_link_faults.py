"""Smoke test of the link-fault benchmark: it runs, and neither binary nor sequenced text suffers."""

from __future__ import annotations

import json

import pytest

from benchmarks import link_faults
from omnibot.protocol import codes


def test_every_command_has_its_own_parameters() -> None:
    ks = [0, 1, 60, 61, 3720, 3721, 100_000, 3_348_899]
    assert [link_faults.unvel(link_faults.vel(k).params()) for k in ks] == ks
    assert link_faults.unvel((5, 5, 1, 100)) is None


def test_quick_run(capsys: pytest.CaptureFixture[str]) -> None:
    assert link_faults.main(["--quick", "--json"]) == 0  # non-zero if anything got through
    outcomes = [link_faults.Outcome(**o) for o in json.loads(capsys.readouterr().out)]
    assert {(o.protocol, o.kind) for o in outcomes} == {
        (p, k) for p in ("text", "binary") for k in link_faults.KINDS
    }
    for o in outcomes:
        if o.kind != "stall":  # stalls are rare: 200 commands may meet none
            assert o.faults > 0, o
        assert (o.corrupted, o.lost_unseen, o.twice, o.false_failures) == (0, 0, 0, 0), o
    assert "binary corrupt 1 %" in link_faults.report(outcomes)


def test_text_without_sequence_numbers_is_seen_to_fail_calls_that_ran() -> None:
    """What the benchmark counts when the controller has no MODE bit 5: a lost reply fails a call
    whose command ran (nothing is sent twice, so nothing runs twice)."""
    o = link_faults.run_one("text", "drop", 0.01, 200, sequenced=False)
    assert o.false_failures > 0 and o.twice == 0 and o.corrupted == 0, o


@pytest.mark.parametrize("kind", ["drop", "corrupt"])
def test_sequenced_text_carries_commands_through_5_percent_of_damaged_bytes(kind: str) -> None:
    """At 5 % of the bytes lost or damaged a text try (a VEL and its reply, about 42 bytes) gets
    through 12 % of the time: with binary's 18 tries 7 % of the commands were given up on, each
    abandoning the window behind it (692 of 1,000 calls failed). With text's own extra tries every
    command set up on a clean line gets through, as binary's do."""
    o = link_faults.run_one("text", kind, 0.05, 200)
    assert (o.corrupted, o.lost_unseen, o.twice, o.false_failures, o.true_failures) == (0, 0, 0, 0, 0), o


def test_bad_arguments(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit):
        link_faults.main(["--commands", "0"])
    assert "--commands must be at least 1" in capsys.readouterr().err


@pytest.mark.parametrize("kind", link_faults.KINDS)
def test_binary_with_the_window_full_lets_nothing_through(kind: str) -> None:
    """32 calls in flight, the whole window the simulated controller announces, at 1 % faults."""
    o = link_faults.run_one("binary", kind, 0.01, 200, waiting_max=codes.WINDOW)
    assert (o.corrupted, o.lost_unseen, o.twice, o.false_failures) == (0, 0, 0, 0), o


def test_waiting_is_bounded(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit):
        link_faults.main(["--waiting", str(codes.WINDOW + 1)])
    assert f"--waiting must be 1..{codes.WINDOW}" in capsys.readouterr().err
