"""A HAL for a desktop process: MicroPython's unix port (or CPython), the UART on stdin/stdout.

For running the real firmware as a child process that a host talks to through pipes (the
conformance suite's MicroPython backend)::

    micropython tests/contract/run_unix.py omni4 [--sonar CM]

* UART: stdin/stdout, non-blocking (``select.poll``; ``os.read``/``os.write`` on CPython,
  byte-wise ``sys.stdin.buffer`` reads on MicroPython). End of input ends :func:`run`.
* Time: ``time.ticks_us`` (MicroPython) or ``time.monotonic_ns`` (CPython).
* Motors: a first-order model per wheel: the rim speed tends to ``pwm / k`` m/s (k: the config's
  PWM counts per m/s) with time constant :data:`TAU` s, so encoders count
  ``rim speed / (2 pi r) * cpr`` per second. No body dynamics, no gyro (the rate reads 0).
* Sonars: every sonar reads a fixed ``sonar_cm`` (-1: no echo) 2 ms after its ping.
* Battery: a constant :data:`BATTERY_MV`.

:func:`main` builds the controller from the config module ``<robot>_config`` (written by
``omnibot.firmware.config.write_config_module`` into a directory on the module path) and polls
it until stdin closes, waiting at most 1 ms for input between polls.
"""

import select
import sys
import time

from omnibot.firmware.controller import Controller
from omnibot.firmware.hal import HAL

TYPE_CHECKING = False
if TYPE_CHECKING:
    from typing import Any

TAU = 0.05  # s, wheel speed time constant
BATTERY_MV = 7400
SONAR_DELAY_US = 2000
TWO_PI = 6.283185307179586

_ticks_us = getattr(time, "ticks_us", None)
_ticks_diff = getattr(time, "ticks_diff", None)


def _now_us() -> int:
    if _ticks_us is not None:
        return int(_ticks_us())
    return time.monotonic_ns() // 1000


class UnixHAL(HAL):
    """stdin/stdout as the UART, simulated wheels and a fixed-range sonar."""

    def __init__(self, config: "dict[str, Any]", sonar_cm: int = -1) -> None:
        n = int(config["motors"])
        self.k = float(config["k"])
        self.radius = [float(r) for r in config["radius"]]
        self.cpr = [int(c) for c in config["encoder_cpr"]]
        self.pwm = [0] * n
        self.speed = [0.0] * n  # rim speed, m/s
        self.counts = [0.0] * n
        self.sonar_cm = sonar_cm
        sonars = len(config["sonar_period_min_ms"])
        self._ping = [-1] * sonars
        self.eof = False
        self._last = _now_us()
        self._poll = select.poll()
        self._poll.register(sys.stdin, select.POLLIN)
        self._os: Any = None
        try:
            import os

            if hasattr(os, "read"):
                self._os = os
        except ImportError:  # pragma: no cover
            pass

    # ---------------------------------------------------------------- time

    def ticks_us(self) -> int:
        """Microseconds from ``time.ticks_us`` (MicroPython) or ``time.monotonic_ns`` (CPython)."""
        return _now_us()

    def ticks_diff(self, a: int, b: int) -> int:
        """``a - b`` in microseconds (``time.ticks_diff`` where it exists)."""
        if _ticks_diff is not None:
            return int(_ticks_diff(a, b))
        return a - b

    # ---------------------------------------------------------------- UART

    def wait(self, ms: int) -> None:
        """Block until input is there or ``ms`` ms passed (keeps the loop from spinning)."""
        self._poll.poll(ms)

    def uart_read(self) -> bytes:
        """The bytes waiting on stdin (b"" when none or at its end, which sets :attr:`eof`); never blocks."""
        if self.eof:
            return b""
        out = b""
        if self._os is not None:
            while self._poll.poll(0):
                data = self._os.read(0, 4096)
                if not data:
                    self.eof = True
                    break
                out += data
            return out
        stdin = sys.stdin.buffer
        while len(out) < 4096 and self._poll.poll(0):
            data = stdin.read(1)
            if not data:
                self.eof = True
                break
            out += data
        return out

    def uart_write(self, data: bytes) -> None:
        """Write ``data`` to stdout."""
        if self._os is not None:
            view = memoryview(data)
            while view:
                n = self._os.write(1, view)
                view = view[n:]
            return
        sys.stdout.buffer.write(data)

    # ---------------------------------------------------------------- motors

    def update(self) -> None:
        """Advance the wheel model to now."""
        now = _now_us()
        dt = self.ticks_diff(now, self._last) / 1e6
        self._last = now
        if dt <= 0:
            return
        a = dt / TAU
        a = min(a, 1.0)
        for i in range(len(self.pwm)):
            target = self.pwm[i] / self.k
            self.speed[i] += (target - self.speed[i]) * a
            self.counts[i] += self.speed[i] * dt / (TWO_PI * self.radius[i]) * self.cpr[i]

    def set_power(self, i: int, pwm: int) -> None:
        """Set motor ``i``'s PWM for the wheel model."""
        self.pwm[i] = pwm

    def encoder_count(self, i: int) -> int:
        """Motor ``i``'s modelled encoder count."""
        return int(self.counts[i])

    def gyro_rate_mdps(self) -> "int | None":
        """No gyro in this model: the rate is always 0."""
        return 0

    # ---------------------------------------------------------------- sonar, battery

    def sonar_start(self, s: int) -> None:
        """Ping sonar ``s`` (its fixed reading is ready SONAR_DELAY_US later)."""
        self._ping[s] = _now_us()

    def sonar_read(self, s: int) -> "int | None":
        """Sonar ``s``'s fixed reading in cm once SONAR_DELAY_US has passed (None before, -1 when not
        pinged)."""
        start = self._ping[s]
        if start < 0:
            return -1
        if self.ticks_diff(_now_us(), start) < SONAR_DELAY_US:
            return None
        self._ping[s] = -1
        return self.sonar_cm

    def battery_mv(self) -> int:
        """The fixed BATTERY_MV."""
        return BATTERY_MV


def run(config: "dict[str, Any]", sonar_cm: int = -1) -> None:
    """Poll the controller until stdin closes."""
    hal = UnixHAL(config, sonar_cm)
    controller = Controller(hal, config)
    while not hal.eof:
        hal.update()
        controller.poll()
        hal.wait(1)


USAGE = "usage: run_unix.py ROBOT [--sonar CM]   (imports the module ROBOT_config)"


def main(argv: "list[str]") -> int:
    """``ROBOT [--sonar CM]``: run the firmware of module ``ROBOT_config``; the exit status."""
    args = list(argv)
    sonar_cm = -1
    if "--sonar" in args:
        i = args.index("--sonar")
        if i + 1 >= len(args):
            print(USAGE)
            return 2
        sonar_cm = int(args[i + 1])
        del args[i : i + 2]
    if len(args) != 1:
        print(USAGE)
        return 2
    module = __import__(args[0] + "_config")
    run(module.CONFIG, sonar_cm)
    return 0
