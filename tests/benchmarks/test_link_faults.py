"""Smoke test of the link-fault benchmark: it runs, it sees what text suffers, binary suffers none."""

from __future__ import annotations

from benchmarks import link_faults


def test_every_command_has_its_own_parameters() -> None:
    ks = [0, 1, 60, 61, 3720, 3721, 100_000, 3_348_899]
    assert [link_faults.unvel(link_faults.vel(k).params()) for k in ks] == ks
    assert link_faults.unvel((5, 5, 1, 100)) is None


def test_quick_run() -> None:
    outcomes = link_faults.run(200, kinds=("drop", "corrupt", "reorder"), rates=(0.01,))
    for o in outcomes:
        assert o.faults > 0, o
        if o.protocol == "binary":
            assert (o.corrupted, o.lost_unseen, o.twice, o.false_failures) == (0, 0, 0, 0), o
    text_harm = sum(
        o.corrupted + o.lost_unseen + o.twice + o.false_failures for o in outcomes if o.protocol == "text"
    )
    assert text_harm > 0  # the benchmark does see what a line without checks lets through
    assert "binary corrupt 1 %" in link_faults.report(outcomes)
