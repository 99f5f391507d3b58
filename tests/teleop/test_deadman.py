"""The deadman: drive while enabled and fresh; repeated zero commands, then silence."""

from __future__ import annotations

import pytest

from omnibot.motion import ZERO, Twist
from omnibot.teleop.deadman import Deadman, Phase, Sample, Why

FWD = Twist(0.5, 0.0, 0.0)


def drive(d: Deadman, t: float) -> None:
    action = d.update(t, Sample(FWD, True, t))
    assert action.twist == FWD


@pytest.mark.parametrize(
    ("sample", "why"),
    [
        (Sample(FWD, False, 1.0), Why.RELEASED),
        (None, Why.LOST),
        (Sample(FWD, True, 0.2), Why.QUIET),  # the newest reading is 0.8 s old
    ],
)
def test_every_end_sends_repeated_zeros_then_nothing(sample: Sample | None, why: Why) -> None:
    d = Deadman(input_timeout=0.5, stop_repeats=3)
    first = d.update(0.0, Sample(FWD, True, 0.0))
    assert first.started and first.twist == FWD
    drive(d, 0.05)
    actions = [d.update(1.0 + 0.05 * i, sample) for i in range(6)]
    assert [a.twist for a in actions] == [ZERO, ZERO, ZERO, None, None, None]
    assert actions[0].ended is why and actions[1].ended is None
    assert d.phase is Phase.IDLE and d.last_end is why


def test_silent_until_enabled() -> None:
    d = Deadman(input_timeout=0.5, stop_repeats=2)
    assert d.update(0.0, None).twist is None
    assert d.update(0.1, Sample(ZERO, False, 0.1)).twist is None


def test_press_again_while_stopping_drives_at_once() -> None:
    d = Deadman(input_timeout=0.5, stop_repeats=5)
    drive(d, 0.0)
    assert d.update(0.05, Sample(FWD, False, 0.05)).twist == ZERO
    again = d.update(0.1, Sample(FWD, True, 0.1))
    assert again.twist == FWD and again.started


def test_enabled_with_stick_centred_holds_zero() -> None:
    d = Deadman(input_timeout=0.5, stop_repeats=2)
    for i in range(5):
        a = d.update(0.05 * i, Sample(ZERO, True, 0.05 * i))
        assert a.twist == ZERO and a.ended is None


def test_bad_arguments() -> None:
    with pytest.raises(ValueError, match="stop_repeats"):
        Deadman(0.5, 0)
