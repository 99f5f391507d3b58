"""A stand-in for the simulator's scanner API (``Simulator.scanner``, ``add_scan_listener``,
``remove_scan_listener``; the scanner branch's Simulator has the same members), and a reader of the
revolutions a scan source gives."""

from __future__ import annotations

import time
from collections.abc import Callable

from omnibot.lidar.reader import ScanSource
from omnibot.scan import Scan


class FakeScanningSim:
    """A simulator whose robot has a scanner section (``model``, ``rays``, ``rate_hz``); the test
    calls ``listeners`` itself. ``scanner`` None: a robot without a scanner."""

    def __init__(self, model: str = "rplidar-a1", rays: int = 200, rate_hz: float = 10.0) -> None:
        spec = type("Spec", (), {"model": model, "rays": rays, "rate_hz": rate_hz})()
        self.robot = type("Robot", (), {"name": "omni4", "scanner": spec})()
        self.scanner: object | None = object()
        self.time = 0.0
        self.listeners: list[Callable[[Scan], None]] = []

    def add_scan_listener(self, fn: Callable[[Scan], None]) -> None:
        self.listeners.append(fn)

    def remove_scan_listener(self, fn: Callable[[Scan], None]) -> None:
        self.listeners.remove(fn)


def read_revolutions(source: ScanSource, count: int, within: float = 30.0) -> list[Scan]:
    """Poll ``source`` until it gave ``count`` scans or ``within`` s of wall time passed (a bound
    for a stuck test, not a timing assertion); the scans (maybe fewer)."""
    got: list[Scan] = []
    deadline = time.monotonic() + within
    while len(got) < count and time.monotonic() < deadline:
        got += source.poll()
        time.sleep(0.02)
    return got
