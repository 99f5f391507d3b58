"""The UNO firmware's battery monitor in simavr, its divider's pin set by the harness (``battery MV``,
the pin's mV: the pack's voltage over the generated BATTERY_DIVIDER, 2.96 on omni4): WARN 19 and 20
once each, the stop latched with WARN 43, motion refused with ERROR 44 until a charged pack and STOP,
as the MicroPython firmware does (tests/firmware/test_battery.py)."""

from __future__ import annotations

import time

from omnibot.protocol import codes

from .conftest import start

DIVIDER = 2.96  # omni4: 14.8 V full scale at 5 V


def pin(volts: float) -> str:
    return f"battery {round(volts * 1000 / DIVIDER)}"


def line(kind: str, code: int) -> str:
    return f"{kind},{code},{codes.TEXTS[code]}"


def test_battery_warns_limits_stops_and_latches() -> None:
    emu, port = start("omni4")
    try:
        assert port.ask("MOVE,30000,100,0,0") == ["OK"]
        emu.command(pin(6.9))
        assert port.lines(1, timeout=15.0) == [line("WARN", codes.W_BATTERY_LOW)]
        emu.command(pin(6.7))
        assert port.lines(1, timeout=15.0) == [line("WARN", codes.W_BATTERY_LIMIT)]
        emu.command(pin(6.3))
        assert port.lines(2, timeout=15.0) == [line("WARN", codes.W_BATTERY_STOP), "IDLE"]
        assert port.ask("STATUS")[0].startswith(f"STATUS,{codes.STATE_BATTERY},")
        assert port.ask("VEL,10,0,0,100") == [line("ERROR", codes.E_BATTERY)]
        assert port.ask("STOP") == ["OK"]  # still flat: the stop holds
        assert port.ask("MOVE,10,40,0,0") == [line("ERROR", codes.E_BATTERY)]
        emu.command(pin(7.4))  # a charged pack
        # once the filter has climbed above stop + hysteresis (the emulator keeps the wall clock: on a
        # loaded machine that takes longer), a STOP clears the latch
        deadline = time.monotonic() + 30.0
        while True:
            assert port.ask("STOP") == ["OK"]
            if port.ask("STATUS")[0].startswith(f"STATUS,{codes.STATE_IDLE},"):
                break
            assert time.monotonic() < deadline, "a charged pack and STOP left the battery stop latched"
            time.sleep(0.05)
        assert port.ask("MOVE,10,40,0,0") == ["OK"]
    finally:
        port.close()
        emu.close()
