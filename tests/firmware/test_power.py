"""The PWM output's whole counts: an open-loop motion's fractional powers dithered over control periods."""

from __future__ import annotations

import math
import statistics

import pytest

from tests.firmware.conftest import Rig, make_rig


def _periods(rig: Rig, command: str, count: int = 100) -> tuple[list[float], list[list[int]]]:
    """Send ``command``; its powers before rounding and the powers applied in each of ``count`` control
    periods after it."""
    assert rig.cmd(command) == ["OK"]
    raw = list(rig.ctrl.executor.model.raw)
    seen = []
    for _ in range(count):
        rig.run(10)  # one control period (omni4: 10 ms)
        seen.append(list(rig.hal.powers))
    return raw, seen


def test_an_open_loop_rotate_averages_its_fractional_powers() -> None:
    """ROTATE at 37 degrees/s asks 38.3 counts of every motor (K = 220, flat factors): rounded it
    would get 38 (-0.8 %); dithered each motor alternates 38 and 39 so that it averages 38.3."""
    raw, seen = _periods(make_rig(pwm_dither=True), "ROTATE,360,37")
    assert 0.1 < raw[0] % 1.0 < 0.9  # not a whole count: what dithering is for
    for i, r in enumerate(raw):
        applied = [s[i] for s in seen]
        assert set(applied) == {math.floor(r), math.ceil(r)}, i
        assert statistics.fmean(applied) == pytest.approx(r, abs=0.02), i


def test_a_move_dithers_and_a_new_command_starts_from_its_rounded_powers() -> None:
    rig = make_rig(pwm_dither=True)
    raw, seen = _periods(rig, "MOVE,300,33,30,0")
    assert any(0.1 < r % 1.0 < 0.9 for r in raw)
    for i, r in enumerate(raw):
        assert statistics.fmean(s[i] for s in seen) == pytest.approx(r, abs=0.02), i
    assert rig.cmd("STOP;MOVE,300,33,30,0") == ["OK", "IDLE", "OK"]
    assert rig.hal.powers == [round(r) for r in raw]  # what it sends first, as without dithering


def test_without_dithering_the_rounded_powers_are_held() -> None:
    """The default (``pwm_dither`` absent): each power rounded once, held."""
    raw, seen = _periods(make_rig(), "ROTATE,360,37")
    assert all(s == [round(r) for r in raw] for s in seen)


def test_dithering_leaves_the_dead_band_and_the_closed_loop_alone() -> None:
    rig = make_rig(pwm_dither=True, power_min=60)  # every wheel's 38.3 counts is below it: all 0 (WARN 12)
    assert rig.cmd("ROTATE,360,37")[1].startswith("WARN,12,")
    rig.run(500)
    assert rig.hal.powers == [0, 0, 0, 0] and not rig.ctrl.executor._drag
    closed = make_rig(pwm_dither=True)
    assert closed.cmd("MODE,2;ROTATE,360,37") == ["OK", "OK"]
    assert not closed.ctrl.executor._drag  # the wheel-speed loop sets the powers itself
