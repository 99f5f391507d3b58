"""The battery monitor: a filtered reading against three thresholds (docs/safety.md#battery).

Every ``PERIOD_MS`` the controller hands :meth:`BatteryMonitor.sample` the HAL's ``battery_mv()``.
A first-order low-pass filter (time constant ``battery_filter_ms``) takes out current spikes: a
motor starting sags the pack for tens of ms, which must not stop a robot. Against the filtered
voltage::

    level 0 ok -> 1 warn (WARN 19) -> 2 limit (WARN 20: the motors' power scaled to
    battery_limit_pct of full) -> 3 stop (WARN 43: motors stopped and latched; motion gets ERROR 44)

A level is entered when the filtered voltage has stayed below its threshold for ``battery_delay_ms``
(as ArduPilot's ``BATT_LOW_TIMER`` and Betaflight's ``vbat_duration_for_warning`` do: a robot
accelerating hard sags its pack for a second or two) and left when it comes back above the threshold
plus ``hysteresis``, so a WARN is sent once per crossing, not once per
ripple. The stop is left only by STOP with the filtered voltage above stop + hysteresis
(:meth:`release`). A reading below half the stop threshold means no battery is measured (a board
without a divider reads 0): it is ignored, and the monitor stays at level 0.

Config keys: ``battery_mv`` [warn, limit, stop, hysteresis] mV (missing or zeros: no monitor),
``battery_filter_ms``, ``battery_delay_ms``, ``battery_limit_pct``.
"""

from omnibot.protocol import codes

TYPE_CHECKING = False
if TYPE_CHECKING:
    from collections.abc import Callable
    from typing import Any

PERIOD_MS = 10
OK = 0
WARNED = 1
LIMITED = 2
STOPPED = 3


class BatteryMonitor:
    """Filter, levels and latch of the battery's low-voltage protection."""

    def __init__(self, cfg: "dict[str, Any]") -> None:
        t = cfg.get("battery_mv") or [0, 0, 0, 0]
        self.warn_mv = int(t[0])
        self.limit_mv = int(t[1])
        self.stop_mv = int(t[2])
        self.hyst_mv = int(t[3])
        self.tau_ms = int(cfg.get("battery_filter_ms", 1000))
        self.delay_ms = int(cfg.get("battery_delay_ms", 3000))
        self.limit_pct = int(cfg.get("battery_limit_pct", 50))
        self.mv = 0.0  # filtered voltage, mV (0: no reading yet)
        self.level = OK
        self._below_ms = 0  # how long the filtered voltage has asked for a lower level
        self._last_ms = 0

    @property
    def latched(self) -> bool:
        """The battery stop is latched (motion refused with ERROR 44)."""
        return self.level == STOPPED

    def sample(self, raw_mv: int, now_ms: int, warn: "Callable[[int], None]") -> bool:
        """Take one reading at ``now_ms``; call ``warn(code)`` for each threshold crossed downwards.
        True when the stop threshold was just reached (the caller stops and latches)."""
        dt = now_ms - self._last_ms
        self._last_ms = now_ms
        if self.stop_mv <= 0 or raw_mv * 2 < self.stop_mv:
            return False
        if self.mv <= 0.0:
            self.mv = float(raw_mv)
        else:
            self.mv += (raw_mv - self.mv) * dt / (self.tau_ms + dt)
        mv = self.mv
        level = self.level
        if level == STOPPED:
            return False
        down = level  # the level the filtered voltage asks for, going down
        if mv < self.stop_mv:
            down = STOPPED
        elif mv < self.limit_mv:
            down = LIMITED
        elif mv < self.warn_mv:
            down = WARNED
        if down > level:
            self._below_ms += dt  # below the next threshold: it must stay there for the delay
            if self._below_ms < self.delay_ms:
                return False
            self._below_ms = 0
            if level < WARNED:
                warn(codes.W_BATTERY_LOW)
            if level < LIMITED <= down:
                warn(codes.W_BATTERY_LIMIT)
            self.level = down
            return down == STOPPED
        self._below_ms = 0
        if level == LIMITED and mv >= self.limit_mv + self.hyst_mv:
            level = WARNED
        if level == WARNED and mv >= self.warn_mv + self.hyst_mv:
            level = OK
        self.level = level
        return False

    def release(self) -> bool:
        """STOP: leave the battery stop if the filtered voltage is back above stop + hysteresis
        (then the level follows the voltage again, without a new WARN). True when not latched."""
        if self.level != STOPPED:
            return True
        if self.mv < self.stop_mv + self.hyst_mv:
            return False
        self._below_ms = 0
        self.level = LIMITED if self.mv < self.limit_mv + self.hyst_mv else WARNED
        return True

    def power_cap(self, pwm_max: int) -> int:
        """The largest power a motor may get at this level."""
        if self.level >= LIMITED:
            return pwm_max * self.limit_pct // 100
        return pwm_max
