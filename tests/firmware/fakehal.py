"""A scripted HAL for firmware tests; MicroPython-compatible (the same file drives both runs).

Time moves only when the test says so (:func:`advance`); UART bytes are fed with :meth:`FakeHAL.send`
and collected with :meth:`FakeHAL.lines`. Encoders follow the applied powers when ``enc_gain``
(counts per PWM count per second) is set, so the closed loop has something to measure.
"""

from omnibot.firmware.hal import HAL

POWER_LOG = 256
"""The latest set_power calls the fake keeps (at least; MicroPython's heap is small)."""


class FakeHAL(HAL):
    def __init__(self, motors: int = 4, sonars: int = 1, gyro: "int | None" = None) -> None:
        self.t = 0
        self.rx = b""
        self.tx = bytearray()
        self.powers = [0] * motors
        self.can_brake = False
        self.braked = [False] * motors
        self.power_log: list[tuple[int, int, int]] = []
        self.enc = [0] * motors
        self.enc_gain = 0.0
        self.enc_offset = 0.0  # PWM counts the fake motor ignores (friction)
        self._enc_acc = [0.0] * motors
        self.track = [0, 0]
        self.gyro = gyro
        self.ranges = [-1] * sonars
        self.sonar_delay_us = 5000
        self.pings = [0] * sonars
        self._ping_at = [-1] * sonars
        self.battery = 7400

    def ticks_us(self) -> int:
        return self.t

    def uart_read(self) -> bytes:
        data = self.rx
        self.rx = b""
        return data

    def uart_write(self, data: bytes) -> None:
        self.tx.extend(data)

    def set_power(self, i: int, pwm: int) -> None:
        self.powers[i] = pwm
        self.braked[i] = False
        self.power_log.append((self.t, i, pwm))
        if len(self.power_log) > 2 * POWER_LOG:  # an open-loop motion's dithered powers change each period
            del self.power_log[:POWER_LOG]

    def brake(self, i: int) -> bool:
        self.braked[i] = self.can_brake
        return self.can_brake

    def encoder_count(self, i: int) -> int:
        return self.enc[i]

    def tracking_count(self, j: int) -> int:
        return self.track[j]

    def gyro_rate_mdps(self) -> "int | None":
        return self.gyro

    def sonar_start(self, s: int) -> None:
        self.pings[s] += 1
        self._ping_at[s] = self.t

    def sonar_read(self, s: int) -> "int | None":
        if self._ping_at[s] < 0:
            return -1
        if self.t - self._ping_at[s] < self.sonar_delay_us:
            return None
        self._ping_at[s] = -1
        return self.ranges[s]

    def battery_mv(self) -> int:
        return self.battery

    # ---------------------------------------------------------------- test side

    def send(self, text: str) -> None:
        self.rx += text.encode()

    def take(self) -> bytes:
        data = bytes(self.tx)
        self.tx = bytearray()
        return data

    def lines(self) -> list[str]:
        """Lines written since the last call (each must end in CR LF)."""
        data = self.take().decode()
        assert data == "" or data.endswith("\r\n"), data
        return data.split("\r\n")[:-1] if data else []

    def move_time(self, dt_us: int) -> None:
        self.t += dt_us
        if self.enc_gain:
            for i in range(len(self.enc)):
                p = self.powers[i]
                eff = 0.0
                if p > self.enc_offset:
                    eff = p - self.enc_offset
                elif p < -self.enc_offset:
                    eff = p + self.enc_offset
                self._enc_acc[i] += eff * self.enc_gain * dt_us * 1e-6
                whole = int(self._enc_acc[i])
                self.enc[i] += whole
                self._enc_acc[i] -= whole


def advance(ctrl: "Controller", hal: FakeHAL, ms: int, step_us: int = 1000) -> None:
    """Poll the controller every step_us for ms milliseconds of scripted time."""
    end = hal.t + ms * 1000
    while hal.t < end:
        hal.move_time(step_us)
        ctrl.poll()


TYPE_CHECKING = False
if TYPE_CHECKING:
    from omnibot.firmware.controller import Controller
