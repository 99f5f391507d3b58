"""Timing core of the firmware command benchmark; runs in CPython and MicroPython alike.

As a script (``micropython firmware_timing.py`` with ``robot_config`` and the staged ``omnibot``
package importable) it prints ``<label> <microseconds per command>`` lines.
"""

import time

from omnibot.firmware.controller import Controller
from omnibot.firmware.hal import HAL

try:
    _ticks = time.ticks_us  # type: ignore[attr-defined]
    _diff = time.ticks_diff  # type: ignore[attr-defined]
except AttributeError:  # CPython

    def _ticks() -> int:
        return time.perf_counter_ns() // 1000

    def _diff(a: int, b: int) -> int:
        return a - b


class FrozenHAL(HAL):
    """Time stands still; output is dropped; input is what the benchmark puts in."""

    def __init__(self) -> None:
        self.rx = b""

    def ticks_us(self) -> int:
        return 0

    def uart_read(self) -> bytes:
        data = self.rx
        self.rx = b""
        return data


CASES = (
    # label, command, behind a long motion (queued commands), commands per batch
    ("MOVE (queued)", "MOVE,20,40,45,10", True, 15),
    ("DELTA (queued)", "DELTA,0,0,10,0,36", True, 15),
    ("ROTATE (queued)", "ROTATE,90,45", True, 15),
    ("POWER (queued)", "POWER,100,10,-20,30", True, 15),
    ("MOVE from idle (starts, powers)", "MOVE,20,40,45,10", False, 1),
    ("VEL (powers)", "VEL,20,-10,30,200", False, 15),
    ("STATUS", "STATUS", False, 15),
    ("HELLO", "HELLO", False, 15),
    ("ERROR 23 unknown", "JUMP,1,2", False, 15),
    ("ERROR 28 speed", "MOVE,20,400,45,10", False, 15),
)


def measure(config: "dict[str, object]", rounds: int = 40) -> "list[tuple[str, float]]":
    """[(label, us per command)] for each case: the best of ``rounds`` batches less the best of as
    many empty polls (each the least: a garbage collection or a preemption lands in one round of
    either, and taking the difference round by round would let it make a case negative)."""
    hal = FrozenHAL()
    ctrl = Controller(hal, config)
    motors = int(config["motors"])  # type: ignore[call-overload]
    results = []
    for label, command, queued, per in CASES:
        cmd = "POWER,100" + ",10" * motors if command.startswith("POWER") else command
        line = (cmd + "\n").encode()
        chunk = line * per
        best = -1
        empty = -1
        for _ in range(rounds):
            ctrl.handle(b"STOP")
            if queued:
                ctrl.handle(b"ROTATE,29999,1")
            ctrl.poll()
            t0 = _ticks()
            ctrl.poll()
            dt = _diff(_ticks(), t0)
            if empty < 0 or dt < empty:
                empty = dt
            hal.rx = chunk
            t0 = _ticks()
            ctrl.poll()
            dt = _diff(_ticks(), t0)
            if best < 0 or dt < best:
                best = dt
        results.append((label, max(0, best - empty) / per))
    ctrl.handle(b"STOP")
    return results


if __name__ == "__main__":
    for label, us in measure(__import__("robot_config").CONFIG):
        print(label + "\t" + str(us))
