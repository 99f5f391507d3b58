"""The motor controller: one :meth:`Controller.poll` per main-loop pass, never blocking.

Each poll: advance the clock from ``hal.ticks_us()``; advance the motion timeline; read the UART
and handle every complete command (immediate ones at once, motion commands into the queue, one
reply each, in order); run the sonars (RANGE events; the guard's speed limit and emergency stop,
safety.py); every 10 ms read the battery (battery.py: WARN 19/20, the power limit, the latched
battery stop); integrate the gyro; send a TEL line when due. Text replies and events are lines ending in CR LF; after ``MODE`` with bit 2 the
same messages travel as binary frames (docs/protocol.md), until a binary MODE clears the bit.
"""

import math

from omnibot.firmware import battery, parser
from omnibot.firmware.binlink import BinaryLink
from omnibot.firmware.calibration import Calibration
from omnibot.firmware.limits import Limits
from omnibot.firmware.motion import Executor
from omnibot.firmware.power import PowerModel
from omnibot.firmware.queue import CommandQueue
from omnibot.firmware.safety import SonarGuard
from omnibot.firmware.sonar import Sonars
from omnibot.firmware.telemetry import Telemetry
from omnibot.protocol import arq, codes, linecheck

TYPE_CHECKING = False
if TYPE_CHECKING:
    from typing import Any

    from omnibot.firmware.hal import HAL
    from omnibot.protocol.frame import Frame

MOTION = (codes.MOVE, codes.ROTATE, codes.DELTA, codes.POWER, codes.VEL)
QUEUED = (codes.MOVE, codes.ROTATE, codes.DELTA, codes.POWER)
SYNC = (codes.STOP, codes.HELLO, codes.MODE)  # sequenced text: taken whatever tag was expected


class Controller:
    """Seed 000's motor controller over a HAL, configured by a plain dict (see config.py)."""

    def __init__(self, hal: "HAL", config: "dict[str, Any]") -> None:
        self.hal = hal
        self.config = config
        self.name = str(config["name"])
        self.motors = int(config["motors"])
        self.tracking = int(config["tracking"])
        self.has_gyro = bool(config["gyro"])
        self.calibration = Calibration(config)
        self.model = PowerModel(config, self.calibration)
        self.limits = Limits(config)
        self.queue = CommandQueue(int(config["queue_capacity"]))
        self.executor = Executor(config, hal, self.queue, self.model, self._warn, self._idle)
        self.sonars = Sonars(len(config["sonar_period_min_ms"]))
        self.guard = SonarGuard(config, self.sonars)
        self.executor.guard = self.guard
        self.telemetry = Telemetry()
        self.link = BinaryLink(hal.uart_write)
        self.binary = False
        self.checked_only = False  # MODE bit 4: text commands need a matching "*" check
        self.sequenced = False  # MODE bit 5: the tags of checked text commands are sequence numbers
        self.text_rx = arq.Receiver(codes.TEXT_SEQ_WINDOW, codes.TEXT_SEQ_MAX)  # their duplicates
        self._kept: bytes | None = None  # sequenced text: the reply being sent, kept for a duplicate
        self.latched = False  # the sonar's emergency stop (the battery's: self.battery.latched)
        self.battery = battery.BatteryMonitor(config)
        self._battery_ms = 0
        self.now_ms = 0
        self._us = 0
        self._seq = 0
        self._last = hal.ticks_us()
        self._split = parser.LineSplitter(int(config["line_max"]))
        self._lines: list[bytes | None] = []
        self._ends: list[int] = []
        self._frames: list[Frame] = []
        self._params: list[int] = []
        self._tag: bytes | None = None  # text: the tag of the command being answered
        self._check = False  # text: it carried a "*" check, so its reply does
        mode = int(config.get("mode", 0))
        if mode & codes.MODE_CLOSED_LOOP and not self.limits.has_encoders:
            mode &= ~codes.MODE_CLOSED_LOOP
        self.executor.set_mode(mode & ~codes.MODE_BINARY)
        self.emit(self._hello_text())
        if self.has_gyro and hal.gyro_fault:  # described, but it did not answer: run on without it
            self.has_gyro = False
            self._warn(codes.W_NO_GYRO)

    # ------------------------------------------------------------------ output

    def emit(self, line: str) -> None:
        """Send one text line (CR LF added)."""
        self.hal.uart_write((line + "\r\n").encode())

    def _reply(self, line: str) -> None:
        """Send a text reply, with the command's tag and a check if it had them."""
        if self._tag is None and not self._check:
            self.emit(line)
            return
        data = line.encode()
        data += linecheck.suffix(data, self._tag, self._check) + b"\r\n"
        if self._kept is not None:
            self._kept = data
        self.hal.uart_write(data)

    def _ok(self) -> None:
        if self.binary:
            self.link.reply(codes.OK, self._seq, [])
        else:
            self._reply("OK")

    def _error(self, code: int) -> None:
        if self.binary:
            self.link.reply(codes.ERROR, self._seq, [code])
        else:
            self._reply(f"ERROR,{code},{codes.TEXTS[code]}")

    def _warn(self, code: int) -> None:
        if self.binary:
            self.link.event(codes.WARN, [code], self.now_ms)
        else:
            self.emit(f"WARN,{code},{codes.TEXTS[code]}")

    def _idle(self) -> None:
        if self.binary:
            self.link.event(codes.IDLE, [], self.now_ms)
        else:
            self.emit("IDLE")

    def _range(self, sonar: int, cm: int) -> None:
        if self.binary:
            self.link.event(codes.RANGE, [sonar, cm], self.now_ms)
        else:
            self.emit(f"RANGE,{sonar},{cm}")

    def _hello_text(self, version: int = codes.PROTOCOL_VERSION) -> str:
        return f"HELLO,{version},{self.name},{self.motors}"

    def _status(self) -> None:
        ex = self.executor
        m = ex.remembered
        state = self.state
        queued = len(self.queue)
        cap = self.queue.capacity
        mode = self.mode
        if self.binary:
            ints = [state, queued, cap, mode]
            ints.extend(ex.powers)
            ints.extend(m)
            self.link.reply(codes.STATUS_REPLY, self._seq, ints)
            return
        powers = ",".join([str(v) for v in ex.powers])
        self._reply(f"STATUS,{state},{queued},{cap},{mode};POWER,{powers};MOVE,{m[0]},{m[1]},{m[2]},{m[3]}")

    # ------------------------------------------------------------------ loop

    @property
    def state(self) -> int:
        """The STATE code reported by STATUS: emergency stop latched, moving or idle."""
        if self.battery.latched:
            return codes.STATE_BATTERY
        if self.latched:
            return codes.STATE_ESTOP
        return codes.STATE_MOVING if self.executor.moving else codes.STATE_IDLE

    @property
    def mode(self) -> int:
        """The MODE bits in force."""
        ex = self.executor
        return (
            ex.mode
            | (codes.MODE_BINARY if self.binary else 0)
            | (codes.MODE_REFUSE_UNCOVERED if self.guard.refuse else 0)
            | (codes.MODE_CHECKED_TEXT if self.checked_only else 0)
            | (codes.MODE_SEQUENCED_TEXT if self.sequenced else 0)
        )

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

    # ------------------------------------------------------------------ input

    def _text_input(self, data: bytes) -> None:
        lines = self._lines
        ends = self._ends
        self._split.feed(data, lines, ends)
        for k in range(len(lines)):
            self.handle(lines[k])
            if self.binary:  # MODE switched to binary: the rest of the bytes are frames
                rest = data[ends[k] :]
                del lines[:]
                del ends[:]
                self._split.reset()
                if rest:
                    self._binary_input(rest)
                return
        del lines[:]
        del ends[:]

    def _binary_input(self, data: bytes) -> None:
        frames = self._frames
        i = 0
        n = len(data)
        while i < n:
            end = data.find(b"\x00", i)
            stop = n if end < 0 else end + 1
            self.link.decoder.feed(data[i:stop], frames)
            i = stop
            for fr in frames:
                self._frame(fr)
            del frames[:]
            if not self.binary:  # a binary MODE cleared bit 2: the rest is text
                if i < n:
                    self._text_input(data[i:])
                return

    def _frame(self, fr: "Frame") -> None:
        t = fr.type_id
        if t < 0:
            return  # bad CRC, COBS or length: dropped, the host retries
        link = self.link
        if t == codes.ACK:
            link.tx.ack(fr.seq)
            return
        if t == codes.HELLO and fr.sync:
            link.rx.reset()
        kind = link.rx.classify(fr.seq, fr.sync)
        if kind == arq.DUPLICATE:
            reply = link.rx.reply_for(fr.seq)
            if reply is not None:
                self.hal.uart_write(reply)
            return
        if kind == arq.OUT_OF_ORDER:
            return
        self._seq = fr.seq
        if t not in codes.PARAM_COUNTS:
            self._error(codes.E_UNKNOWN)
            return
        try:
            ints, _ = fr.fields()
        except ValueError:
            self._error(codes.E_NOT_INTEGER)
            return
        if len(ints) > codes.params_max(t):
            self._error(codes.E_PARAM_COUNT)
            return
        for v in ints:
            if v < codes.INT_MIN or v > codes.INT_MAX:
                self._error(codes.E_RANGE16)
                return
        self.execute(t, ints)

    def handle(self, cmd: "bytes | None") -> None:
        """Handle one text command (None: it was too long); exactly one reply, which echoes the
        command's ``#tag`` and carries a ``*`` check if the command did (a bad check: ERROR 26,
        untagged, nothing run)."""
        self._tag = None
        self._check = False
        if cmd is None:
            self._error(codes.E_TOO_LONG)
            return
        end, tag_start, tag_end, checked = linecheck.split(cmd)
        if checked == linecheck.BAD_CHECK:
            self._error(codes.E_CHECKSUM)
            return
        p = self._params
        kw = parser.parse(cmd[:end] if end < len(cmd) else cmd, p)
        if kw == 0:
            return
        if self.checked_only and checked != linecheck.CHECKED:
            # MODE bit 4: only what the check covers runs; a line cut short by a damaged byte (a
            # digit turned into ";" or CR) or a suffix damaged out of recognition has none
            self._error(codes.E_CHECK_REQUIRED)
            return
        seq = 0
        if tag_start >= 0:
            self._tag = cmd[tag_start:tag_end]
            if checked == linecheck.CHECKED:
                for i in range(tag_start, tag_end):
                    seq = seq * 10 + cmd[i] - 48
        self._check = checked == linecheck.CHECKED
        sequenced = self.sequenced and self._check and self._tag is not None
        if sequenced and not self._in_sequence(kw, seq):
            self._tag = None
            self._check = False
            return
        self._kept = b"" if sequenced or (self._check and kw == codes.MODE) else None
        if kw < 0:
            self._error(-kw)
        else:
            self.execute(kw, p)
        if self._kept is not None and self._check and self._tag is not None:
            if not sequenced and self.sequenced:  # the MODE that set bit 5 starts the sequence
                self.text_rx.reset()
                self.text_rx.classify(seq, True)
            if self.sequenced:
                self.text_rx.remember(seq, self._kept)
        self._kept = None
        self._tag = None
        self._check = False

    def _in_sequence(self, kw: int, seq: int) -> bool:
        """Sequenced text (MODE bit 5): whether the checked command tagged ``seq`` is new and runs.
        A duplicate (one of the last TEXT_SEQ_WINDOW tags) gets its kept reply again and does not
        run; one out of order (after a lost line) is dropped unanswered: the host's retransmission
        restores the order (arq.Receiver, as binary frames). STOP, HELLO and MODE are new whatever
        tag was expected, and HELLO starts the sequence afresh (a new session)."""
        rx = self.text_rx
        if kw == codes.HELLO:
            rx.reset()
        kind = rx.classify(seq, kw in SYNC)
        if kind == arq.NEW:
            return True
        if kind == arq.DUPLICATE:
            reply = rx.reply_for(seq)
            if reply is not None:
                self.hal.uart_write(reply)
        return False

    # ------------------------------------------------------------------ commands

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
