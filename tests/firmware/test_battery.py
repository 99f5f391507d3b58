"""The battery monitor (firmware/battery.py) and its place in the controller: WARN 19/20 once per
crossing, the power limit, the latched battery stop (WARN 43, ERROR 44, STATUS state 4) released by
STOP only with the voltage back up; current spikes filtered out."""

from __future__ import annotations

from omnibot.firmware.battery import LIMITED, OK, WARNED, BatteryMonitor
from omnibot.firmware.config import build_config
from omnibot.protocol import codes
from omnibot.robot import load_robot
from tests.firmware.conftest import Rig, make_rig


def warn(code: int) -> str:
    return f"WARN,{code},{codes.TEXTS[code]}"


def err(code: int) -> str:
    return f"ERROR,{code},{codes.TEXTS[code]}"


def test_thresholds_come_from_the_description() -> None:
    cfg = build_config(load_robot("omni4"))  # 2S Li-Po: 3.5 / 3.4 / 3.3 V a cell, 0.05 hysteresis
    assert cfg["battery_mv"] == [7000, 6800, 6600, 100]
    assert (cfg["battery_filter_ms"], cfg["battery_delay_ms"], cfg["battery_limit_pct"]) == (1000, 3000, 50)
    assert build_config(load_robot("omni3"))["battery_mv"][:3] == [21000, 20400, 19800]  # 6S


def feed(mon: BatteryMonitor, mv: int, ms: int, t0: int, codes_out: list[int]) -> int:
    stopped = 0
    for t in range(t0 + 10, t0 + ms + 1, 10):
        if mon.sample(mv, t, codes_out.append):
            stopped = t
    return stopped


def test_levels_once_per_crossing_with_delay_and_hysteresis() -> None:
    mon = BatteryMonitor(build_config(load_robot("omni4")))
    out: list[int] = []
    feed(mon, 7400, 1000, 0, out)
    assert mon.level == OK and out == []
    feed(mon, 6950, 8000, 1000, out)
    assert mon.level == WARNED and out == [codes.W_BATTERY_LOW]
    feed(mon, 7050, 8000, 9000, out)  # above warn, inside the hysteresis: still warned, no new WARN
    assert mon.level == WARNED and out == [codes.W_BATTERY_LOW]
    feed(mon, 6990, 8000, 17000, out)
    assert out == [codes.W_BATTERY_LOW]
    feed(mon, 7150, 8000, 25000, out)  # above warn + hysteresis: cleared, the next fall warns again
    assert mon.level == OK
    feed(mon, 6700, 8000, 33000, out)
    assert mon.level == LIMITED and out == [codes.W_BATTERY_LOW] * 2 + [codes.W_BATTERY_LIMIT]
    assert mon.power_cap(255) == 127


def test_a_spike_does_not_stop_and_a_sag_must_last() -> None:
    mon = BatteryMonitor(build_config(load_robot("omni4")))
    out: list[int] = []
    feed(mon, 7400, 1000, 0, out)
    assert feed(mon, 5000, 100, 1000, out) == 0  # a motor's start: 100 ms at 5 V, not even a WARN
    assert mon.level == OK and out == []
    assert feed(mon, 5000, 1000, 1100, out) == 0  # 1 s at 5 V: filtered below stop, but not for 3 s
    feed(mon, 7400, 5000, 2100, out)
    assert mon.level == OK and out == []
    t = feed(mon, 6400, 10000, 7100, out)  # a flat pack under load
    # the filter falls below 7.0 V after 0.5 s and stays below a threshold from then on: 3 s later
    # it is at 6.43 V, below stop, and the levels are entered at once
    assert 7100 + 3300 <= t <= 7100 + 3700 and mon.latched
    assert out == [codes.W_BATTERY_LOW, codes.W_BATTERY_LIMIT]


def test_no_battery_measured_means_no_monitor() -> None:
    mon = BatteryMonitor(build_config(load_robot("omni4")))
    out: list[int] = []
    assert feed(mon, 0, 10000, 0, out) == 0 and out == [] and mon.level == OK
    assert BatteryMonitor({}).sample(1000, 10, out.append) is False


def drain(rig: Rig, mv: int, ms: int) -> list[str]:
    rig.hal.battery = mv
    return rig.run(ms)


def test_controller_limits_power_then_stops_and_latches() -> None:
    rig = make_rig()
    rig.run(100)
    assert rig.cmd("MOVE,30000,100,0,0") == ["OK"]
    full = max(abs(p) for p in rig.hal.powers)
    assert drain(rig, 6900, 5000) == [warn(codes.W_BATTERY_LOW)]
    assert max(abs(p) for p in rig.hal.powers) == full
    assert drain(rig, 6700, 5000) == [warn(codes.W_BATTERY_LIMIT)]
    assert max(abs(p) for p in rig.hal.powers) <= 127 < full
    assert drain(rig, 6400, 5000) == [warn(codes.W_BATTERY_STOP), "IDLE"]
    assert rig.hal.powers == [0] * 4
    assert rig.status().startswith(f"STATUS,{codes.STATE_BATTERY},")
    for motion in ("MOVE,10,40,0,0", "ROTATE,90,90", "VEL,10,0,0,100", "POWER,100,50,50,50,50"):
        assert rig.cmd(motion) == [err(codes.E_BATTERY)]
    assert rig.cmd("STOP") == ["OK"]  # motors off, but the pack is still flat: the latch holds
    assert rig.cmd("MOVE,10,40,0,0") == [err(codes.E_BATTERY)]
    drain(rig, 6650, 5000)  # above stop, inside the hysteresis
    rig.cmd("STOP")
    assert rig.cmd("MOVE,10,40,0,0") == [err(codes.E_BATTERY)]
    assert drain(rig, 7400, 8000) == []  # a fresh pack: no WARN on the way up
    assert rig.cmd("STOP") == ["OK"]
    assert rig.status().startswith(f"STATUS,{codes.STATE_IDLE},")
    assert rig.cmd("MOVE,10,40,0,0") == ["OK"]


def test_battery_stop_while_idle_and_sonar_latch_kept_apart() -> None:
    rig = make_rig()
    rig.run(100)
    assert drain(rig, 6000, 6000) == [
        warn(codes.W_BATTERY_LOW),
        warn(codes.W_BATTERY_LIMIT),
        warn(codes.W_BATTERY_STOP),
        "IDLE",
    ]
    assert rig.cmd("VEL,10,0,0,100") == [err(codes.E_BATTERY)]
