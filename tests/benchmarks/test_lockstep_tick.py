"""The lockstep tick benchmark: its run is deterministic, and timing its parts does not change it."""

from __future__ import annotations

from benchmarks import lockstep_tick


def test_timing_the_parts_leaves_the_run_as_it_was() -> None:
    parts: dict[str, float] = {}
    cpu, ticks, digest = lockstep_tick.run()
    _, ticks_timed, digest_timed = lockstep_tick.run(parts)
    assert ticks > 20_000 and cpu > 0.0
    assert (ticks_timed, digest_timed) == (ticks, digest)
    assert set(parts) == {"firmware", "simulator", "wall"}
    assert 0 < parts["simulator"] < parts["wall"] and 0 < parts["firmware"] < parts["wall"]
