"""What the controller tells the runtime between cycles: telemetry and events.

:class:`Listening` is the runtime's listener on its client (:meth:`Runtime.start
<omnibot.runtime.runtime.Runtime.start>` adds it): each telemetry sample updates the clock offset, the
battery, the controller's state (a latched stop) and the estimator, then the telemetry hooks; a WARN
may be a latched stop or the battery running low. Both are kept for the next cycle (at most
:data:`KEEP`).
"""

from __future__ import annotations

from collections import deque

from omnibot.client import Event, Telemetry, WarnEvent
from omnibot.estimation import Estimator
from omnibot.protocol import codes
from omnibot.runtime.core import RuntimeCore, log

KEEP = 1000
"""Telemetry samples and events kept for the next cycle: the newest, when nobody cycled for a while
(a standstill, a scripted manoeuvre)."""
BATTERY_TEXTS = {
    codes.W_BATTERY_LOW: "battery low (below its warning threshold): finish and charge it",
    codes.W_BATTERY_LIMIT: "battery very low (below its limit threshold): the motors' power is limited",
}


class Listening(RuntimeCore):
    """The runtime's telemetry and event listeners."""

    estimator: Estimator | None
    _offset: float
    _offset_time: float
    _telemetry: deque[Telemetry]
    _events: deque[Event]

    def _on_telemetry(self, event: Telemetry) -> None:
        self.samples += 1
        lag = event.time - event.controller_time
        # the least-delayed sample gives the clock offset (allowed to creep up 20 us/s for drift)
        self._offset = min(self._offset + 2e-5 * max(0.0, event.time - self._offset_time), lag)
        self._offset_time = event.time
        if event.battery is not None:
            self._battery = event.battery
        if event.state is not None:
            self.state = event.state
            if event.state == codes.STATE_ESTOP:
                self._latch()
            elif event.state == codes.STATE_BATTERY:
                self._latch("battery")
            elif self.latched:
                self.latched = False
                self.latch_reason = ""
        if self.estimator is not None:
            self.estimator.update(event)
            alerts = self.estimator.alerts
            while alerts:
                self.notify("warn", alerts.pop(0), "estimator")
        for hook in list(self.telemetry_hooks):
            try:
                hook(event)
            except Exception:  # a hook (a recorder's) never keeps a sample from the loop
                log.exception("a telemetry hook failed; it is removed")
                if hook in self.telemetry_hooks:
                    self.telemetry_hooks.remove(hook)
        self._telemetry.append(event)

    def _on_event(self, event: Event) -> None:
        if isinstance(event, WarnEvent):
            if event.code == codes.W_SONAR_STOP:
                self._latch()
            elif event.code == codes.W_BATTERY_STOP:
                self._latch("battery")
            elif event.code in BATTERY_TEXTS:
                volts = self.last_battery
                at = f" at {volts:.2f} V" if volts is not None else ""
                self.notify("warn", BATTERY_TEXTS[event.code].replace(":", f"{at}:", 1), "controller")
        self._events.append(event)

    @property
    def last_battery(self) -> float | None:
        """The battery voltage of the newest telemetry that carried it, V."""
        return self._battery
