"""The simulated battery runs down with the motors' current (coulomb counting on the Li-Po curve), in
lockstep: a small pack drives until the firmware warns (19, 20), stops and latches (43, state 4,
motion refused with ERROR 44), and only a charged pack lets STOP release it."""

from __future__ import annotations

import pytest

from omnibot.client import BatteryStopLatched, EventRecorder, RobotClient, WarnEvent
from omnibot.protocol import codes
from omnibot.robot import RobotDescription, load_robot, open_voltage
from omnibot.sim.device import SimDevice
from omnibot.sim.physics import Physics
from omnibot.transport import LockstepLink


def small_pack(charge: float, capacity_ah: float) -> RobotDescription:
    robot = load_robot("omni4")
    battery = robot.battery.model_copy(update={"charge": charge, "capacity_ah": capacity_ah})
    return robot.model_copy(update={"battery": battery})


def test_open_voltage_follows_the_lipo_curve() -> None:
    assert open_voltage("lipo", 2, 1.0) == pytest.approx(8.4)
    assert open_voltage("lipo", 2, 0.2) == pytest.approx(7.4)
    assert open_voltage("lipo", 2, 0.0) == pytest.approx(6.54)
    assert open_voltage("lipo", 3, 0.5) == pytest.approx(11.55)


def test_physics_drains_with_current_and_ideal_battery_does_not() -> None:
    ideal = Physics(load_robot("omni4"))
    drains = Physics(small_pack(0.5, 0.01))
    for ph in (ideal, drains):
        for _ in range(1000):
            ph.step([[200, 200, 200, 200]])
    assert ideal.battery_charge[0] == 1.0 and ideal.battery_open_voltage[0] == 7.4
    used = 0.5 - drains.battery_charge[0]  # 1 s at a few A from 36 As
    assert 0.02 < used < 0.3
    assert drains.battery_open_voltage[0] == pytest.approx(open_voltage("lipo", 2, drains.battery_charge[0]))


def test_driving_runs_the_pack_flat_and_the_stop_latches() -> None:
    device = SimDevice(small_pack(0.12, 0.02), seed=1)  # 0.12 of 72 As: a few seconds of driving
    rec = EventRecorder()
    with RobotClient(LockstepLink(device), small_pack(0.12, 0.02), timeout=2.0) as client:
        client.add_listener(rec)
        client.telemetry(0.05, codes.TEL_BATTERY | codes.TEL_QUEUE)
        client.vel(0.4, 0.0, 0.0, 0.3)
        t0 = device.sim.time
        while device.sim.time - t0 < 30.0 and codes.W_BATTERY_STOP not in [w.code for w in rec.of(WarnEvent)]:
            try:
                client.vel(0.4, 0.0, 0.0, 0.3)
            except BatteryStopLatched:
                break
            client.sleep(0.1)
        warns = [w.code for w in rec.of(WarnEvent) if w.code >= codes.W_BATTERY_LOW]
        assert warns == [codes.W_BATTERY_LOW, codes.W_BATTERY_LIMIT, codes.W_BATTERY_STOP]
        assert device.sim.time - t0 < 20.0
        client.sleep(0.2)
        assert device.sim.battery_charge < 0.05
        assert client.status().battery_stop
        with pytest.raises(BatteryStopLatched):
            client.vel(0.2, 0.0, 0.0, 0.3)
        client.stop()  # the pack is still flat: the stop holds
        assert client.status().battery_stop
        device.sim.physics.battery_charge = [1.0]  # type: ignore[attr-defined]  # a charged pack
        client.sleep(5.0)
        client.stop()
        status = client.status()
        assert not status.estop and not status.battery_stop
        client.vel(0.2, 0.0, 0.0, 0.3)
