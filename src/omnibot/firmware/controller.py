"""The motor controller: one :meth:`Controller.poll` per main-loop pass, never blocking.

Each poll: advance the clock from ``hal.ticks_us()``; advance the motion timeline; read the UART
and handle every complete command (immediate ones at once, motion commands into the queue, one
reply each, in order); run the sonars (RANGE events; the guard's speed limit and emergency stop,
safety.py); every 10 ms read the battery (battery.py: WARN 19/20, the power limit, the latched
battery stop); integrate the gyro; send a TEL line when due. Text replies and events are lines ending in CR LF; after ``MODE`` with bit 2 the
same messages travel as binary frames (docs/protocol.md), until a binary MODE clears the bit.

:class:`Controller` is composed of one part per concern, each a mixin over the shared
:class:`~omnibot.firmware.controller_state.ControllerState` (on MicroPython flattened into one class,
:func:`~omnibot.firmware.mixins.flat`):

==========================  ==================================================================
``controller_input.py``     text lines and binary frames in, tags, checks and sequence numbers
``controller_commands.py``  each command checked and run
``controller_replies.py``   replies and events out, as text or binary frames
==========================  ==================================================================
"""

from omnibot.firmware import battery
from omnibot.firmware.controller_commands import Commands
from omnibot.firmware.controller_input import Input
from omnibot.firmware.controller_replies import Replies
from omnibot.firmware.mixins import flat
from omnibot.protocol import codes

TYPE_CHECKING = False
if TYPE_CHECKING:
    from typing import Any

    from omnibot.firmware.hal import HAL


class Controller(Input, Commands, Replies):
    """Seed 000's motor controller over a HAL, configured by a plain dict (see config.py)."""

    def __init__(self, hal: "HAL", config: "dict[str, Any]") -> None:
        self._init_state(hal, config)
        mode = int(config.get("mode", 0))
        if mode & codes.MODE_CLOSED_LOOP and not self.limits.has_encoders:
            mode &= ~codes.MODE_CLOSED_LOOP
        self.executor.set_mode(mode & ~codes.MODE_BINARY)
        self.emit(self._hello_text())
        if self.has_gyro and hal.gyro_fault:  # described, but it did not answer: run on without it
            self.has_gyro = False
            self._warn(codes.W_NO_GYRO)

    # ------------------------------------------------------------------ loop

    def poll(self) -> None:
        """One pass of the main loop."""
        hal = self.hal
        t = hal.ticks_us()
        dt = max(hal.ticks_diff(t, self._last), 0)
        self._last = t
        us = self._us + dt
        if us >= 1000:
            self.now_ms += us // 1000
            us %= 1000
        self._us = us
        self.executor.step(dt)
        self._check_halt()
        data = hal.uart_read()
        if data:
            if self.binary:
                self._binary_input(data)
            else:
                self._text_input(data)
        if self.sonars.count:
            fresh = self.sonars.poll(hal, self.now_ms, self._range)
            if fresh:
                self._sonar_readings(fresh)
        if self.now_ms - self._battery_ms >= battery.PERIOD_MS:
            self._battery_ms = self.now_ms
            self._battery_sample()
        if self.has_gyro:
            rate = hal.gyro_rate_mdps()
            if rate is not None:
                self.telemetry.integrate(rate, dt)
        if self.telemetry.due(self.now_ms):
            fields = self.telemetry.fields(self)
            if self.binary:
                self.link.telemetry(fields)
            else:
                self.emit("TEL," + ",".join([str(v) for v in fields]))
        if self.binary:
            self.link.poll(self.now_ms)

    def _sonar_readings(self, fresh: int) -> None:
        """New readings (bit s: sonar s): the guard re-limits a travel or calls the emergency stop."""
        g = self.guard
        for s in range(self.sonars.count):
            if fresh & (1 << s):
                g.reading(s, self.sonars.last[s])
        ex = self.executor
        if not ex.moving:
            return
        if ex.travelling:
            self._relimit()
        elif g.below_stop():  # ROTATE, POWER: the threshold alone
            self.emergency_stop()

    def _relimit(self) -> None:
        """The guard's inputs changed (a reading, SONAR, MODE): limit the running travel anew."""
        self.executor.relimit()
        self._check_halt()

    def _check_halt(self) -> None:
        """Report a motion the guard stopped (executor.halt): the emergency stop, or an uncovered one."""
        code = self.executor.halt
        if not code:
            return
        self.executor.halt = 0
        if code == codes.W_SONAR_STOP:
            self.emergency_stop()
        else:
            self._warn(codes.W_UNCOVERED_STOP)
            self._idle()

    def _battery_sample(self) -> None:
        """One battery reading: WARN 19/20 on a crossing, the power cap, the latched battery stop."""
        mon = self.battery
        if mon.sample(self.hal.battery_mv(), self.now_ms, self._warn):
            self.executor.stop()
            self.executor.brake()
            self._warn(codes.W_BATTERY_STOP)
            self._idle()
        ex = self.executor
        cap = mon.power_cap(ex.pwm_max)
        if cap != ex.power_cap:
            ex.power_cap = cap
            ex.apply()

    def emergency_stop(self) -> None:
        """Sonar emergency stop: motors off (braked where the HAL can), queue cleared, WARN 13,
        latched until STOP."""
        self.executor.stop()
        self.executor.brake()
        self.latched = True
        self._warn(codes.W_SONAR_STOP)
        self._idle()


if not TYPE_CHECKING:
    Controller = flat(Controller)  # one class on MicroPython (mixins.py)
