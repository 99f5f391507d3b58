"""``omnibot sim --pty`` with a scanner: a second pty serving the emulated RPLIDAR, read by the
rplidar driver (through RplidarScanner), the controller's line first as before."""

from __future__ import annotations

import io
import math
import threading
from collections.abc import Callable
from typing import Any, cast

import numpy as np
import pytest

from omnibot.lidar import A1, A2, RplidarDevice, RplidarScanner, open_scanner
from omnibot.lidar.rplidar_codec import Command, Request, encode_request
from omnibot.robot import RobotDescription, load_robot
from omnibot.scan import Scan
from omnibot.sim import emulator
from omnibot.transport import LockstepLink, open_link
from tests.lidar.fakes import FakeScanningSim, read_revolutions

ANSWER_WAIT = 5.0
"""s the driver waits for each answer of an emulator in this very process: on a machine shared with
other workers the emulator's thread can be off the CPU for over the driver's 1 s default (CI saw
"Descriptor length mismatch": GET_INFO's 7 bytes not all in within 1 s)."""


class Lines(io.StringIO):
    """stdout of the emulator, whose lines a test waits for."""

    def __init__(self) -> None:
        super().__init__()
        self.flushed = threading.Event()

    def flush(self) -> None:
        super().flush()
        if self.getvalue():
            self.flushed.set()


def start(run: Callable[[], int], out: Lines) -> tuple[threading.Thread, list[object]]:
    """``run`` in a thread; its status (or what it raised) lands in the list, and ends the wait."""
    result: list[object] = []

    def main() -> None:
        try:
            result.append(run())
        except BaseException as exc:
            result.append(exc)
            out.flushed.set()

    thread = threading.Thread(target=main)
    thread.start()
    return thread, result


def test_scanner_device_follows_the_description() -> None:
    sim = FakeScanningSim("rplidar-a2", rays=360, rate_hz=20.0)
    device = emulator.scanner_device(sim, 0.001)  # type: ignore[arg-type]
    assert device is not None and device.model is A2 and sim.listeners == []
    link = LockstepLink(device, baud=A2.baud)
    link.write(encode_request(Request(Command.SCAN)))
    link.advance(0.005)
    assert sim.listeners == [device.feed]  # measuring only while a host scans
    link.write(encode_request(Request(Command.STOP)))
    link.advance(0.005)
    assert sim.listeners == []
    assert device.sample_rate == A2.sample_rate  # 7200 rays/s resampled to the A2's 4000 nodes/s
    a1 = emulator.scanner_device(FakeScanningSim("some-lidar", rays=360, rate_hz=5.5), 0.001)  # type: ignore[arg-type]
    assert a1 is not None and a1.model is A1 and a1.sample_rate == pytest.approx(1980.0)
    none = FakeScanningSim()
    none.scanner = None
    assert emulator.scanner_device(none, 0.001) is None  # type: ignore[arg-type]


def test_sim_pty_serves_the_scanner_on_a_second_pty(monkeypatch: pytest.MonkeyPatch) -> None:
    """The robot presets have no scanner on this branch: the device is put in through scanner_device,
    fed a revolution every 0.1 s of device time as the simulator's scanner would."""
    fed: list[int] = []

    class Fed(RplidarDevice):
        def step(self) -> None:
            super().step()
            if self.time >= len(fed) * 0.1:
                ranges = np.full(200, 1.0 + len(fed))
                self.feed(Scan(self.time, 0.0, 2 * math.pi / 200, ranges, 0.1, 12.0, scan_time=0.1))
                fed.append(len(fed))

    monkeypatch.setattr(emulator, "scanner_device", lambda sim, tick: Fed(A1, tick=tick))
    out, stop = Lines(), threading.Event()
    thread, status = start(lambda: emulator.run_pty_emulator(load_robot("omni4"), stop=stop, out=out), out)
    try:
        assert out.flushed.wait(120.0)  # a start takes seconds on a loaded machine
        first, second = out.getvalue().splitlines()
        assert first.startswith("/dev/") and second.startswith("scanner /dev/")
        scanner = RplidarScanner(second.split()[1], timeout=ANSWER_WAIT)
        try:
            got = read_revolutions(scanner, 2)
        finally:
            scanner.close()
        assert len(got) >= 2 and all(len(s) == 200 for s in got)
        assert [float(s.ranges[0]) for s in got[1:]] == [float(s.ranges[0]) + 1 for s in got[:-1]]
    finally:
        stop.set()
        thread.join(30.0)
    assert status == [0] and not thread.is_alive()


def test_a_fleet_prints_a_scanner_line_per_robot_after_its_own_lines(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(emulator, "scanner_device", lambda sim, tick: RplidarDevice(A1, tick=tick))
    members = [
        emulator.parse_member(text, k, 0)
        for k, text in enumerate(["omni4?name=a&pose=1,1,0", "omni3?name=b&pose=2.6,1.05,0"])
    ]
    out, stop = Lines(), threading.Event()
    thread, status = start(lambda: emulator.run_pty_fleet(members, world="room", stop=stop, out=out), out)
    try:
        assert out.flushed.wait(120.0)
    finally:
        stop.set()
        thread.join(30.0)
    lines = [line.split() for line in out.getvalue().splitlines()]
    assert [name for name, _ in lines] == ["a", "b", "a/scanner", "b/scanner"]
    assert all(path.startswith("/dev/") for _, path in lines)
    assert status == [0] and not thread.is_alive()


def robot_with_scanner() -> RobotDescription:
    """omni4, whose preset has a scanner once the simulated scanner is in (skip before)."""
    robot = load_robot("omni4")
    if getattr(robot, "scanner", None) is None:
        pytest.skip("the omni4 preset has no scanner section yet (the simulated scanner's branch)")
    return robot


def test_the_simulated_scanner_read_through_its_pty() -> None:
    robot = robot_with_scanner()
    out, stop = Lines(), threading.Event()
    thread, status = start(lambda: emulator.run_pty_emulator(robot, world="room", stop=stop, out=out), out)
    try:
        assert out.flushed.wait(120.0)
        scanner_line = out.getvalue().splitlines()[1]
        with RplidarScanner(scanner_line.split()[1], timeout=ANSWER_WAIT) as scanner:
            got = read_revolutions(scanner, 2)
    finally:
        stop.set()
        thread.join(30.0)
    assert status == [0] and len(got) >= 2
    for scan in got:
        finite = scan.ranges[np.isfinite(scan.ranges)]
        assert len(finite) > 0.9 * len(scan)  # a closed room: almost every ray returns
        assert finite.max() < 12.0


def test_the_simulated_scanner_in_process_on_a_sim_link() -> None:
    robot = robot_with_scanner()
    link = open_link("sim://omni4?world=room")
    assert isinstance(link, LockstepLink)
    try:
        source = open_scanner(None, link, robot)
        link.advance(0.5)
        scans = source.poll()
        source.close()
    finally:
        link.close()
    rays = cast(Any, robot).scanner.rays
    assert scans and all(len(s) == rays for s in scans)
    assert [s.stamp for s in scans] == sorted(s.stamp for s in scans)
