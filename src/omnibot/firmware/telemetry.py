"""Periodic TEL lines: ``TEL,<t_ms>,<mask>`` then the groups the mask picks, in bit order.

Groups (protocol/codes.py TEL_*): 1 powers ``n,p1..pn``; 2 motor encoders ``n,c1..cn``; 4 tracking
wheels ``m,k1..km``; 8 yaw rate in 0.01 deg/s; 16 integrated yaw in 0.01 deg (not wrapped); 32
battery mV; 64 ``state,queued``; 128 sonars ``k,r1..rk`` (last range, cm, -1 none). Lines are sent
every P ms on a fixed timeline.
"""

from omnibot.protocol import codes

NANODEG_PER_CDEG = 10000000  # mdps * us = 1e-9 degree; 0.01 degree = 1e7 of them


class Telemetry:
    """TEL scheduling, the yaw integrator and line formatting."""

    def __init__(self) -> None:
        self.period = 0
        self.mask = 0
        self._next = 0
        self.heading_cdeg = 0
        self._rem = 0
        self.rate_mdps = 0

    def configure(self, period: int, mask: int, now_ms: int) -> None:
        """Send TEL every ``period`` ms (0: off) with the groups of ``mask``, the first one due now."""
        self.period = period
        self.mask = mask
        self._next = now_ms

    def integrate(self, rate_mdps: int, dt_us: int) -> None:
        """Integrate the gyro's yaw rate into the heading, integers only."""
        self.rate_mdps = rate_mdps
        self._rem += rate_mdps * dt_us
        whole = self._rem // NANODEG_PER_CDEG
        if whole:
            self.heading_cdeg += whole
            self._rem -= whole * NANODEG_PER_CDEG

    def due(self, now_ms: int) -> bool:
        """Whether a TEL line is due at ``now_ms``; advances the schedule (skipping missed periods)."""
        if self.period == 0 or now_ms - self._next < 0:
            return False
        self._next += self.period
        if now_ms - self._next >= 0:
            self._next = now_ms + self.period
        return True

    def fields(self, ctrl: "Controller") -> "list[int]":
        """The TEL fields after the keyword: t_ms, mask, then the groups of the mask in bit order."""
        mask = self.mask
        hal = ctrl.hal
        f = [ctrl.now_ms & 0xFFFFFFFF, mask]
        n = ctrl.motors
        if mask & codes.TEL_POWER:
            f.append(n)
            f.extend(ctrl.executor.powers)
        if mask & codes.TEL_ENCODERS:
            f.append(n)
            for i in range(n):
                f.append(_i32(hal.encoder_count(i)))
        if mask & codes.TEL_TRACKING:
            f.append(ctrl.tracking)
            for j in range(ctrl.tracking):
                f.append(_i32(hal.tracking_count(j)))
        if mask & codes.TEL_GYRO:
            r = self.rate_mdps
            f.append(r // 10 if r >= 0 else -((-r) // 10))
        if mask & codes.TEL_HEADING:
            f.append(_i32(self.heading_cdeg))
        if mask & codes.TEL_BATTERY:
            f.append(hal.battery_mv())
        if mask & codes.TEL_QUEUE:
            f.append(ctrl.state)
            f.append(len(ctrl.queue))
        if mask & codes.TEL_SONAR:
            sonars = ctrl.sonars
            f.append(sonars.count)
            f.extend(sonars.last)
        return f


def _i32(v: int) -> int:
    """v as a wrapping signed 32-bit counter."""
    if -2147483648 <= v <= 2147483647:
        return v
    return (v + 2147483648) % 4294967296 - 2147483648


TYPE_CHECKING = False
if TYPE_CHECKING:
    from omnibot.firmware.controller import Controller
