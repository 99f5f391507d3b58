"""The controller's commands: each parsed command checked against the limits and run, one reply each.

Motion commands are refused while an emergency stop is latched (ERROR 40, or the battery's); MOVE,
ROTATE, DELTA and POWER go into the queue (ERROR 21 when full) and start at once when the executor
is idle; everything else acts at once.
"""

import math

from omnibot.firmware.controller_state import ControllerState
from omnibot.protocol import codes

MOTION = (codes.MOVE, codes.ROTATE, codes.DELTA, codes.POWER, codes.VEL)
QUEUED = (codes.MOVE, codes.ROTATE, codes.DELTA, codes.POWER)


class Commands(ControllerState):
    """The controller's command dispatch and the commands that need more than one call."""

    def execute(self, kw: int, p: "list[int]") -> None:
        """Check and run one parsed command; exactly one reply."""
        code = self.limits.check(kw, p)
        if code == 0 and kw in MOTION:
            if self.battery.latched:
                code = codes.E_BATTERY
            elif self.latched:
                code = codes.E_ESTOP
        if code == 0 and self.guard.refuse and not self._covered(kw, p):
            code = codes.E_UNCOVERED
        if code:
            self._error(code)
            return
        ex = self.executor
        if kw in QUEUED:
            if not self.queue.push(kw, p):
                self._error(codes.E_QUEUE_FULL)
                return
            self._ok()
            ex.step(0)
            self._check_halt()
        elif kw == codes.VEL:
            self._ok()
            n = len(p)  # 4, 5 (version 3's A) or 7 (version 4's AX, AY, AW)
            ex.vel(p[0], p[1], p[2], p[3], p[4] if n == 5 else 0, p[4:] if n == 7 else None)
            self._check_halt()
        elif kw == codes.STOP:
            was = ex.stop()
            ex.reset_move()
            self.latched = False
            self.battery.release()  # only with the voltage back above stop + hysteresis
            self._ok()
            if was:
                self._idle()
        elif kw == codes.STATUS:
            self._status()
        elif kw == codes.HELLO:
            self._reply_hello(p)
        elif kw == codes.MODE:
            self._set_mode(p[0])
        elif kw == codes.SONAR:
            self.sonars.configure(p[0] - 1, p[1], p[2], p[3], p[4], self.now_ms)
            self.guard.clear(p[0] - 1)
            self._ok()
            self._relimit()
        elif kw == codes.TELEM:
            self.telemetry.configure(p[0], p[1], self.now_ms)
            self._ok()
        elif kw == codes.CAL:
            if self._cal(p[0], p[1], p[2], p[3]):
                self._ok()
            else:
                self._error(codes.E_CALIBRATION)
        else:
            self._error(codes.E_INTERNAL)

    def _reply_hello(self, p: "list[int]") -> None:
        """HELLO: the reply with the highest protocol version the host's list ``p`` shares."""
        version = 0  # the highest one the host's list shares (limits: there is one)
        for v in p:
            if v in codes.VERSIONS and v > version:
                version = v
        if version == 0:  # a bare HELLO: the version every host speaks
            version = codes.PROTOCOL_VERSION
        if self.binary:
            self.link.reply(
                codes.HELLO_REPLY,
                self._seq,
                [version, self.motors, self.link.rx.window],
                self.name.encode(),
            )
        else:
            self._reply(self._hello_text(version))

    def _set_mode(self, bits: int) -> None:
        """MODE: acknowledge, then set the refusal, the text checks, the executor's mode and the link."""
        self._ok()
        self.guard.refuse = bool(bits & codes.MODE_REFUSE_UNCOVERED)
        self.checked_only = bool(bits & codes.MODE_CHECKED_TEXT)
        self.sequenced = bool(bits & codes.MODE_SEQUENCED_TEXT)
        self.executor.set_mode(bits & (codes.MODE_SIMULATION | codes.MODE_CLOSED_LOOP))
        self._relimit()
        binary = bool(bits & codes.MODE_BINARY)
        if binary != self.binary:
            self.binary = binary
            self.link.reset()
            self._split.reset()
            self.text_rx.reset()

    def _covered(self, kw: int, p: "list[int]") -> bool:
        """A MOVE or VEL travels where an armed sonar looks (or does not travel); others: True."""
        if kw == codes.MOVE:
            if p[0] == 0:
                return True
            a = math.radians(p[2])
            s = 1.0 if (p[0] > 0) == (p[1] > 0) else -1.0
            return self.guard.covers(s * math.cos(a), s * math.sin(a))
        if kw == codes.VEL and (p[0] or p[1]):
            return self.guard.covers(float(p[0]), float(p[1]))
        return True

    def _cal(self, table: int, index: int, x: int, y: int) -> bool:
        if table == codes.CAL_K:
            return index == 0 and x == 0 and self.calibration.set_knot(table, 0, 0, y * 0.1)
        if table in (codes.CAL_ROLLER_COS, codes.CAL_ROLLER_SIN, codes.CAL_SPEED):
            return self.calibration.set_knot(table, index, x, y * 0.1)
        if table == codes.CAL_ROLLER_COAST:  # signed: seconds x 1000
            return x >= 0 and self.calibration.set_knot(table, index, x, y / codes.CAL_SCALE)
        if table == codes.CAL_REACH:  # cm/s
            return self.calibration.set_knot(table, index, x, float(y))
        if table == codes.CAL_SLIP:  # the floor's creep: a closed-loop landing's travel (landing.py)
            return x == 0 and self.executor.landing.set_slip(index, y)
        if x < 0 or y < 0:
            return False
        if table == codes.CAL_OFFSET:
            return self.calibration.set_knot(table, index, x, y * 0.1)
        if (
            codes.CAL_KL + codes.CAL_KL_CURVES <= table < codes.CAL_GAIN
            or table >= codes.CAL_GAIN + codes.CAL_MOTORS
        ):
            return False
        return self.calibration.set_knot(table, index, x, y / codes.CAL_SCALE)
