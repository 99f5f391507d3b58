"""Seed 000's K_r and K_t read off a calibration section (pure arithmetic on hand-made tables)."""

from __future__ import annotations

import pytest

from omnibot.calibration.seedterms import seed_kr, seed_kt
from omnibot.errors import ConfigError
from omnibot.robot import CalibrationSpec, MotorMapSpec, PiecewiseLinear

K = 150.0
KT = PiecewiseLinear(x=(10.0, 100.0), y=(1.2, 1.4))
KR = PiecewiseLinear(x=(10.0, 100.0), y=(0.6, 0.9))
POWERS = [10.0, 40.0, 100.0]


def spec(offsets: tuple[float, ...] | None = None, gain: float = 1.0, speed: float = 0.0) -> CalibrationSpec:
    motors = None
    if offsets is not None:
        flat = PiecewiseLinear(x=(0.0,), y=(gain,))
        motors = MotorMapSpec(offset=offsets, gain=(flat,) * len(offsets), speed=(speed,) * len(offsets))
    return CalibrationSpec(k=K, k_t=KT, k_r=KR, motors=motors)


def test_without_a_motor_map_they_are_the_tables() -> None:
    assert seed_kr(spec(), POWERS) == pytest.approx([KR(p) for p in POWERS])
    assert seed_kt(spec(), POWERS, moving=80.0) == pytest.approx([KT(p) for p in POWERS])


def test_the_offsets_count_in_rotation_not_in_a_turn_added_to_a_motion() -> None:
    """A ROTATE's motors start from rest, so seed 000's K_r carries their start: the mean offset over
    the power; the turn of a curved MOVE is added to wheels already past it."""
    offsets = (30.0, 40.0, 50.0, 40.0)
    assert seed_kr(spec(offsets), POWERS) == pytest.approx([KR(p) + 40.0 / p for p in POWERS])
    assert seed_kt(spec(offsets), POWERS, moving=80.0) == pytest.approx([KT(p) for p in POWERS])


def test_gain_and_speed_term_count_in_both() -> None:
    s = spec((0.0, 0.0, 0.0, 0.0), gain=1.1, speed=12.0)
    assert seed_kr(s, POWERS) == pytest.approx([1.1 * KR(p) + 12.0 / K for p in POWERS])
    assert seed_kt(s, POWERS, moving=80.0) == pytest.approx([1.1 * KT(p) + 12.0 / K for p in POWERS])


@pytest.mark.parametrize(
    ("call", "message"),
    [
        (lambda: seed_kr(CalibrationSpec(k=K, k_t=KT), POWERS), "both tables"),
        (lambda: seed_kr(spec(), [0.0, 10.0]), "positive"),
        (lambda: seed_kt(spec(), [], moving=80.0), "positive"),
        (lambda: seed_kt(spec(), POWERS, moving=0.5), "at least 1"),
    ],
)
def test_what_cannot_be_read_is_refused(call: object, message: str) -> None:
    with pytest.raises(ConfigError, match=message):
        call()  # type: ignore[operator]
