"""The battery protection on every backend: a nominal pack is reported and changes nothing; on the
backends whose pack a test can set (the lockstep simulator's open-circuit voltage, the UNO's ADC pin
in simavr) a flat pack warns, stops and latches with its own reason until a charged pack and STOP.
The pty emulator and the MicroPython process read a fixed nominal pack (skipped there);
tests/firmware/test_battery.py covers the MicroPython firmware's logic in-process."""

from __future__ import annotations

import pytest

from omnibot.client import BatteryStopLatched, EventRecorder, RobotClient, Telemetry, WarnEvent
from omnibot.protocol import codes

from .conftest import Backend


def test_a_nominal_pack_is_reported_and_changes_nothing(client: RobotClient) -> None:
    samples: list[Telemetry] = []
    client.add_listener(lambda e: samples.append(e) if isinstance(e, Telemetry) else None)
    rec = EventRecorder()
    client.add_listener(rec)
    client.telemetry(0.05, codes.TEL_BATTERY | codes.TEL_QUEUE)
    client.sleep(0.5)
    client.telemetry(0)
    volts = [s.battery for s in samples if s.battery is not None]
    assert volts and all(6.9 < v < 7.6 for v in volts)  # omni4's 7.4 V pack, above its 7.0 V warning
    assert all(s.state != codes.STATE_BATTERY for s in samples)
    assert not [w for w in rec.of(WarnEvent) if w.code in (19, 20, 43)]


def test_a_flat_pack_stops_and_latches_until_charged(client: RobotClient, backend: Backend) -> None:
    if backend.battery is None:
        pytest.skip(f"{backend.name} backend: its pack cannot be set (a fixed nominal reading)")
    rec = EventRecorder()
    client.add_listener(rec)
    try:
        backend.battery(client.link, 6.3)  # below omni4's 6.6 V stop
        end = client.clock.now() + 15.0
        while client.clock.now() < end and codes.W_BATTERY_STOP not in [w.code for w in rec.of(WarnEvent)]:
            client.sleep(0.1)
        warns = [w.code for w in rec.of(WarnEvent)]
        assert warns[-3:] == [codes.W_BATTERY_LOW, codes.W_BATTERY_LIMIT, codes.W_BATTERY_STOP]
        assert client.status().battery_stop
        with pytest.raises(BatteryStopLatched) as info:
            client.move(0.1, 0.4)
        assert info.value.code == codes.E_BATTERY
        client.stop()
        assert client.status().battery_stop  # still flat: STOP does not release it
    finally:
        backend.battery(client.link, 7.4)
        client.sleep(3.0)  # the filter climbs back above stop + hysteresis
        client.stop()
    assert client.status().idle
    client.move(0.05, 0.4)
    client.wait_idle(timeout=3)
