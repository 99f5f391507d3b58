"""The simulator's numbers, bit for bit: the seeded scenes of :mod:`tests.sim.step_trace` against the
trace recorded before the step was compiled whole (every float compared by its bits)."""

from __future__ import annotations

import pytest

from .step_trace import SCENES, assert_as_recorded


@pytest.mark.parametrize("scene", sorted(SCENES))
def test_the_step_gives_the_recorded_numbers_bit_for_bit(scene: str) -> None:
    assert_as_recorded(scene)
