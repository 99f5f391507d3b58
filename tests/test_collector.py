"""The garbage collector while a command starts (:mod:`omnibot.collector`): held by the process's own
command line, released (start-up frozen, thresholds back) by the loop that follows."""

from __future__ import annotations

import gc
from collections.abc import Iterator

import pytest

from omnibot import cli, collector


@pytest.fixture
def freezes(monkeypatch: pytest.MonkeyPatch) -> Iterator[list[int]]:
    """``gc.freeze`` calls counted, not made (the test process keeps its own generations); the
    thresholds as they were afterwards, whatever the test left."""
    calls: list[int] = []
    monkeypatch.setattr(gc, "freeze", lambda: calls.append(1))
    monkeypatch.setattr(collector, "_HOLD", collector._Hold())
    before = gc.get_threshold()
    try:
        yield calls
    finally:
        gc.set_threshold(*before)


def test_a_hold_raises_the_first_threshold_and_a_release_freezes_and_restores(freezes: list[int]) -> None:
    before = gc.get_threshold()
    collector.hold()
    assert collector.held()
    assert gc.get_threshold() == (collector.START_THRESHOLD, *before[1:])
    collector.hold()  # held already: what is restored stays the first
    collector.release()
    assert not collector.held() and gc.get_threshold() == before and freezes == [1]
    collector.release()  # not held: nothing
    assert freezes == [1] and gc.get_threshold() == before


def test_a_release_without_a_hold_changes_nothing(freezes: list[int]) -> None:
    before = gc.get_threshold()
    collector.release()
    assert freezes == [] and gc.get_threshold() == before and not collector.held()


def test_a_start_releases_at_its_end_unless_its_loop_did(freezes: list[int]) -> None:
    before = gc.get_threshold()
    with pytest.raises(RuntimeError), collector.starting():
        assert collector.held()
        raise RuntimeError("the command failed")
    assert not collector.held() and gc.get_threshold() == before and freezes == [1]
    with collector.starting():
        collector.release()  # the command's loop began
        assert gc.get_threshold() == before and freezes == [1, 1]
    assert freezes == [1, 1] and gc.get_threshold() == before


def test_only_the_processs_own_command_line_holds(
    freezes: list[int], monkeypatch: pytest.MonkeyPatch
) -> None:
    seen: list[bool] = []

    def command(argv: object) -> int:
        seen.append(collector.held())
        return 0

    monkeypatch.setattr(cli, "_main", command)
    assert cli.main() == 0 and cli.main(["robot", "list"]) == 0
    assert seen == [True, False] and not collector.held() and freezes == [1]
