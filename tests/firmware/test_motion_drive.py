"""The executor's drive (motion_drive.py): what a twist feeds each wheel on the closed loop."""

from __future__ import annotations

import pytest

from omnibot.sim import SimDevice


def test_a_wheel_that_mostly_turns_the_body_is_fed_what_turns_it_on_the_closed_loop() -> None:
    """omni4's arc (0.3 m/s turning at 0.5 rad/s): its two wheels that only turn the body (rim 0.049
    m/s) are fed at least ROTATE's K K_r at their own speed (the turning part's flat K_t gave them
    8-14 counts where 33-37 turn them); the driving pair keeps the power model's feedforward."""
    dev = SimDevice("omni4", surface="wood", seed=1)
    ex = dev.controller.executor
    cal = ex.model.cal
    dev.command("MODE,2", 0.02)
    dev.command("VEL,30,0,29,200", 0.02)
    turning = [i for i, row in enumerate(ex.model.rim) if abs(row[0] * 0.3) < 1e-9]
    assert len(turning) == 2
    for i in range(ex.n):
        u = abs(ex._target[i] * ex._radius[i])
        if i in turning:
            assert abs(ex._ff[i]) == pytest.approx(cal.k * cal.k_r(cal.k * u) * u)
            assert abs(ex._ff[i]) > 2.5 * abs(ex.model.raw[i])  # K_t's was under 0.4 of it
        else:
            assert ex._ff[i] == pytest.approx(ex.model.raw[i])
