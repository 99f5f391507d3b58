"""Smoke test of the attack and fault suite: its quick run of the in-process families, and its report."""

from __future__ import annotations

import json

import pytest

from benchmarks import attack_suite


def test_quick_in_process_families(capsys: pytest.CaptureFixture[str]) -> None:
    attack_suite.main(["--quick", "--only", "fuzz,bits,links", "--json"])
    rows = [attack_suite.Row(**r) for r in json.loads(capsys.readouterr().out)]
    by_name = {r.name: r for r in rows}
    assert {r.family for r in rows} == {"fuzz", "bits", "links"}
    for r in rows:
        if r.family == "fuzz" and r.name.startswith("MicroPython"):
            assert r.counts["inputs"] == 300 and r.wrong == 0, r
        if r.family == "bits":
            assert r.counts["errors tried"] > 0
        if r.family == "links" and r.name.startswith("binary"):
            assert r.wrong == 0 and r.counts["faults"] > 0, r  # binary lets nothing through
    assert by_name["binary frames (28), every single bit"].wrong == 0
    checked = by_name["checked text, every single bit, MODE bit 4 set (client default)"]
    assert checked.counts["ran a command not sent"] == 0
    table = attack_suite.report(rows)
    assert "**1. Fuzzing both firmwares**" in table and "| wrong | note |" in table


def test_unknown_family_is_named(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit):
        attack_suite.main(["--only", "bits,disks"])
    assert "unknown family disks" in capsys.readouterr().err


def test_the_link_watch_counts_only_lines_run_without_a_check() -> None:
    """MODE bit 4 clear: a line with a valid check is verified anyway and a refused line ran
    nothing; only a line that ran without a check is what the bit is there to stop."""
    from omnibot.protocol import text
    from omnibot.protocol.messages import Vel
    from omnibot.sim import SimDevice

    controller = SimDevice("omni4", seed=1).controller
    watch = attack_suite._watch(controller)
    attack_suite._watches.remove(watch)
    checked = text.encode(Vel(10, 0, 0, 100), tag=3).strip()
    controller.handle(checked)  # runs, checked
    controller.handle(checked[:-1] + (b"0" if checked[-1:] != b"0" else b"1"))  # bad check: refused
    controller.handle(b"VEX,10,0,0,100")  # unknown: refused
    assert watch.unguarded == 0
    controller.handle(b"VEL,10,0,0,100#4")  # tagged, its check cut away: runs unchecked
    assert (watch.unguarded, watch.example) == (1, b"VEL,10,0,0,100#4")
