"""The simulator's numbers, bit for bit: the seeded scenes of :mod:`tests.sim.step_trace` against the
trace recorded before the step was compiled whole (every float compared by its bits)."""

from __future__ import annotations

import json

import pytest

from .step_trace import GOLDEN, SCENES


@pytest.mark.parametrize("scene", sorted(SCENES))
def test_the_step_gives_the_recorded_numbers_bit_for_bit(scene: str) -> None:
    expected = json.loads(GOLDEN.read_text(encoding="utf-8"))[scene]
    got = json.loads(json.dumps(SCENES[scene]()))
    for key, rows in expected.items():
        if isinstance(rows, list):
            assert len(got[key]) == len(rows), key
            for k, (row, want) in enumerate(zip(got[key], rows, strict=True)):
                assert row == want, f"{scene} {key}[{k}]"
        else:
            assert got[key] == rows, key
