"""The hardware abstraction layer: everything the firmware asks of a board or of the simulator.

The controller calls only these methods, all non-blocking::

    ticks_us() -> int               microsecond counter; may wrap, see ticks_diff
    ticks_diff(a, b) -> int         a - b in microseconds, wrap-aware (default: plain a - b)
    uart_read() -> bytes            whatever bytes have arrived, possibly b""
    uart_write(data: bytes)         queue bytes for sending
    set_power(i, pwm)               motor i (0-based) to signed PWM counts -pwm_max..pwm_max;
                                    positive turns the wheel the way that carries the robot along the
                                    wheel's drive direction (the robot description's sign convention);
                                    0 opens the driver (the motor coasts)
    brake(i) -> bool                short motor i's terminals through the driver (dynamic braking)
                                    until the next set_power; False: this driver cannot (it coasts)
    encoder_count(i) -> int         cumulative count of motor i's encoder, same sign as its power
    tracking_count(j) -> int        cumulative count of passive tracking wheel j
    gyro_rate_mdps() -> int | None  yaw rate in millidegrees/s, counter-clockwise positive; None: no gyro
    sonar_start(s)                  trigger a ping of sonar s (0-based)
    sonar_read(s) -> int | None     range in cm of the last ping, -1 for no echo, None while waiting
    battery_mv() -> int             battery voltage in millivolts

:class:`HAL` is the base with harmless defaults (no sensors); the simulator's device and the tests'
FakeHAL subclass it. :class:`MachineHAL` drives a MicroPython board (RP2040, ESP32) through the
``machine`` module, with a pin map from ``robot_config.py`` (keys below):

    "uart": [id, tx, rx] or None       hardware UART at config "baud"; None: USB stdin/stdout
    "motors": [[pwm, in1, in2], ...]   L298-style channel: PWM on the enable pin, direction on in1/in2
                                       (in2 -1: a single direction pin, PWM/DIR drivers)
    "pwm_freq": 1000                   PWM frequency, Hz
    "encoders": [[a, b], ...] or []    quadrature encoders of the motors, counted on A's edges
    "tracking": [[a, b], ...]          tracking-wheel encoders
    "sonars": [[trig, echo], ...]      HC-SR04: 10 us trigger pulse, echo timed by edge interrupts
    "battery": [adc_pin, mv_per_lsb]   ADC pin and millivolts per read_u16() count (divider included)
    "gyro": [i2c_id, scl, sda, address, freq, fs_sel, dlpf_cfg] or None
                                       MPU6050 (firmware/mpu6050.py) on I2C bus i2c_id at address 0x68
                                       or 0x69, bus clock freq Hz, range FS_SEL (0: +-250 deg/s), DLPF_CFG
                                       (3: 42 Hz); [i2c_id, scl, sda] alone: 0x68, 400 kHz, 0, 3

A gyro that does not answer at boot (or is not an MPU6050) leaves the board without one:
``gyro_fault`` says why, :meth:`HAL.gyro_rate_mdps` answers None, and the controller sends WARN 10
after its HELLO instead of crashing.
"""

from omnibot.firmware.mpu6050 import MPU6050, GyroError


class HAL:
    """Base HAL: a board without sensors. Subclasses override what they have."""

    gyro_fault: "str | None" = None
    """Why the gyro the board was given does not work (None: it works, or there is none)."""

    def ticks_us(self) -> int:
        """A free-running microsecond counter (wraps on a board; use :meth:`ticks_diff`)."""
        raise NotImplementedError

    def ticks_diff(self, a: int, b: int) -> int:
        """``a - b`` in microseconds, correct across the counter's wrap."""
        return a - b

    def uart_read(self) -> bytes:
        """The bytes received since the last call (b"" when none); never blocks."""
        return b""

    def uart_write(self, data: bytes) -> None:
        """Send ``data`` to the host."""
        pass

    def set_power(self, i: int, pwm: int) -> None:
        """Drive motor ``i`` at signed ``pwm`` counts (the sign is the direction)."""
        pass

    def brake(self, i: int) -> bool:
        """Short motor ``i``'s terminals to brake it; False when the driver cannot."""
        return False

    def encoder_count(self, i: int) -> int:
        """Cumulative quadrature count of motor ``i``'s encoder."""
        return 0

    def tracking_count(self, j: int) -> int:
        """Cumulative count of tracking wheel ``j``'s encoder."""
        return 0

    def gyro_rate_mdps(self) -> "int | None":
        """The gyro's yaw rate in millidegrees/s, None without a gyro."""
        return None

    def sonar_start(self, s: int) -> None:
        """Trigger sonar ``s``'s ping."""
        pass

    def sonar_read(self, s: int) -> "int | None":
        """Sonar ``s``'s last range in cm: -1 for no echo, None while the echo is still awaited."""
        return -1

    def battery_mv(self) -> int:
        """The battery voltage in mV (0 when not measured)."""
        return 0


ECHO_TIMEOUT_US = 30000  # HC-SR04: about 5 m and back
US_PER_CM = 58  # round trip at 343 m/s


class _Quadrature:
    """x2 quadrature counting: an interrupt on both edges of A, direction from B."""

    def __init__(self, machine: "Any", a: int, b: int) -> None:
        self.count = 0
        self._a = machine.Pin(a, machine.Pin.IN, machine.Pin.PULL_UP)
        self._b = machine.Pin(b, machine.Pin.IN, machine.Pin.PULL_UP)
        self._a.irq(self._edge, machine.Pin.IRQ_RISING | machine.Pin.IRQ_FALLING)

    def _edge(self, pin: "Any") -> None:
        if self._a.value() == self._b.value():
            self.count -= 1
        else:
            self.count += 1


class _Sonar:
    """HC-SR04 with the echo timed by edge interrupts (seed 000 V.E), never blocking the loop."""

    def __init__(self, machine: "Any", time: "Any", trig: int, echo: int) -> None:
        self._time = time
        self._trig = machine.Pin(trig, machine.Pin.OUT, value=0)
        self._echo = machine.Pin(echo, machine.Pin.IN)
        self._echo.irq(self._edge, machine.Pin.IRQ_RISING | machine.Pin.IRQ_FALLING)
        self._start = 0
        self._rise = 0
        self._width = -1
        self._waiting = False

    def _edge(self, pin: "Any") -> None:
        t = self._time.ticks_us()
        if self._echo.value():
            self._rise = t
        elif self._waiting and self._rise:
            self._width = self._time.ticks_diff(t, self._rise)

    def start(self) -> None:
        self._rise = 0
        self._width = -1
        self._waiting = True
        self._start = self._time.ticks_us()
        self._trig.value(1)
        self._time.sleep_us(10)
        self._trig.value(0)

    def read(self) -> "int | None":
        if not self._waiting:
            return -1
        if self._width >= 0:
            self._waiting = False
            return self._width // US_PER_CM
        if self._time.ticks_diff(self._time.ticks_us(), self._start) > ECHO_TIMEOUT_US:
            self._waiting = False
            return -1
        return None


class MachineHAL(HAL):
    """HAL of a MicroPython board, from the pin map described in this module's docstring."""

    def __init__(
        self, pins: "dict[str, Any]", baud: int = 115200, pwm_max: int = 255, clock: "Any" = None
    ) -> None:
        """``clock``: a module with ticks_us, ticks_diff and sleep_us (default MicroPython's time)."""
        machine = __import__("machine")
        self._time = clock if clock is not None else __import__("time")
        self._pwm_max = pwm_max
        self._motors = []
        for pwm_pin, in1, in2 in pins["motors"]:
            pwm = machine.PWM(machine.Pin(pwm_pin))
            pwm.freq(pins.get("pwm_freq", 1000))
            pwm.duty_u16(0)
            d1 = machine.Pin(in1, machine.Pin.OUT, value=0)
            d2 = machine.Pin(in2, machine.Pin.OUT, value=0) if in2 >= 0 else None
            self._motors.append((pwm, d1, d2))
        self._enc = [_Quadrature(machine, a, b) for a, b in pins.get("encoders", [])]
        self._track = [_Quadrature(machine, a, b) for a, b in pins.get("tracking", [])]
        self._sonars = [_Sonar(machine, self._time, t, e) for t, e in pins.get("sonars", [])]
        self._adc = None
        self._mv_per_lsb = 0.0
        battery = pins.get("battery")
        if battery:
            self._adc = machine.ADC(machine.Pin(battery[0]))
            self._mv_per_lsb = float(battery[1])
        self._i2c = None
        self._gyro: MPU6050 | None = None
        gyro = pins.get("gyro")
        if gyro:
            self._start_gyro(machine, list(gyro) + [0x68, 400000, 0, 3][len(gyro) - 3 :])
        uart = pins.get("uart")
        self._uart = None
        self._poll = None
        if uart:
            self._uart = machine.UART(
                uart[0], baudrate=baud, tx=machine.Pin(uart[1]), rx=machine.Pin(uart[2])
            )
        else:
            sys = __import__("sys")
            select = __import__("select")
            self._stdin = sys.stdin.buffer
            self._stdout = sys.stdout.buffer
            self._poll = select.poll()
            self._poll.register(sys.stdin, select.POLLIN)

    def _start_gyro(self, machine: "Any", g: "list[int]") -> None:
        """Open the I2C bus and wake the MPU6050 on it; on any failure keep the reason in
        ``gyro_fault`` and go on without a gyro."""
        try:
            self._i2c = machine.I2C(g[0], scl=machine.Pin(g[1]), sda=machine.Pin(g[2]), freq=g[4])
            self._gyro = MPU6050(self._i2c, g[3], g[5], g[6])
        except (GyroError, OSError, ValueError) as exc:
            self._gyro = None
            self.gyro_fault = "gyro: " + str(exc)

    def ticks_us(self) -> int:
        """``time.ticks_us()``: wraps, compare with :meth:`ticks_diff`."""
        return int(self._time.ticks_us())

    def ticks_diff(self, a: int, b: int) -> int:
        """``time.ticks_diff(a, b)``: ``a - b`` in microseconds across the wrap."""
        return int(self._time.ticks_diff(a, b))

    def uart_read(self) -> bytes:
        """The bytes waiting on the hardware UART, or on USB stdin when there is none; never blocks."""
        if self._uart is not None:
            if self._uart.any():
                return bytes(self._uart.read())
            return b""
        assert self._poll is not None
        out = b""
        while self._poll.poll(0):
            out += self._stdin.read(1)
        return out

    def uart_write(self, data: bytes) -> None:
        """Send ``data`` on the hardware UART, or on USB stdout when there is none."""
        if self._uart is not None:
            self._uart.write(data)
        else:
            self._stdout.write(data)

    def set_power(self, i: int, pwm: int) -> None:
        """Set motor ``i``'s direction pins by the sign of ``pwm`` and its enable pin's duty by its size."""
        pwm_out, d1, d2 = self._motors[i]
        d1.value(1 if pwm > 0 else 0)
        if d2 is not None:
            d2.value(1 if pwm < 0 else 0)
        duty = abs(pwm) * 65535 // self._pwm_max
        pwm_out.duty_u16(duty if duty < 65535 else 65535)

    def brake(self, i: int) -> bool:
        """L298-style channel: both direction inputs low with the enable full on shorts the motor
        ("fast motor stop"); a PWM/DIR driver (one direction pin) cannot brake."""
        pwm_out, d1, d2 = self._motors[i]
        if d2 is None:
            return False
        d1.value(0)
        d2.value(0)
        pwm_out.duty_u16(65535)
        return True

    def encoder_count(self, i: int) -> int:
        """Motor ``i``'s encoder count (0 for a motor without one)."""
        return int(self._enc[i].count) if i < len(self._enc) else 0

    def tracking_count(self, j: int) -> int:
        """Tracking wheel ``j``'s encoder count (0 when there is none)."""
        return int(self._track[j].count) if j < len(self._track) else 0

    def gyro_rate_mdps(self) -> "int | None":
        """The MPU6050's yaw rate in millidegrees/s (read over I2C), None without a gyro or when
        this read failed on the bus (the controller then skips the sample)."""
        if self._gyro is None:
            return None
        try:
            return int(self._gyro.rate_mdps())
        except OSError:
            return None

    def sonar_start(self, s: int) -> None:
        """Send sonar ``s``'s 10 us trigger pulse (nothing for a sonar the board lacks)."""
        if s < len(self._sonars):
            self._sonars[s].start()

    def sonar_read(self, s: int) -> "int | None":
        """Sonar ``s``'s range in cm from its timed echo: -1 for no echo (or no such sonar), None while
        awaited."""
        return self._sonars[s].read() if s < len(self._sonars) else -1

    def battery_mv(self) -> int:
        """The battery voltage in mV from the ADC (divider included), 0 without one."""
        if self._adc is None:
            return 0
        return int(self._adc.read_u16() * self._mv_per_lsb)


TYPE_CHECKING = False
if TYPE_CHECKING:
    from typing import Any
