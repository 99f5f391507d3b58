"""A register-level model of the MPU6050 and an I2C bus to hang it on; runs in CPython and MicroPython.

:class:`FakeMPU6050` answers register reads and writes as the chip does (InvenSense RM-MPU-6000A):
128 eight-bit registers, reads and writes that auto-increment the register address, WHO_AM_I 0x68
(read-only), PWR_MGMT_1 0x40 at power-up (asleep: the data registers read 0 until woken), DEVICE_RESET
(bit 7) back to the power-up values, GYRO_ZOUT from the rate the test sets, scaled by GYRO_CONFIG's
FS_SEL, rounded and saturated at the int16 limits. Not modelled: the DLPF's filtering (CONFIG is only
stored), the accelerometer, the FIFO, interrupts.

:class:`FakeI2C` has ``machine.I2C``'s memory calls; an address with no chip raises ``OSError(5)``
(EIO, as MicroPython's rp2 port does for a NACK); ``fail`` makes every transfer fail (a bus that broke).
"""

WHO_AM_I = 0x75
PWR_MGMT_1 = 0x6B
GYRO_CONFIG = 0x1B
GYRO_ZOUT_H = 0x47
GYRO_OUT = 0x43  # GYRO_XOUT_H .. GYRO_ZOUT_L: six bytes
LSB_PER_DPS = (131.0, 65.5, 32.8, 16.4)


class FakeMPU6050:
    """One chip. ``rate_dps``: the yaw rate it measures (deg/s, counter-clockwise positive)."""

    def __init__(self, who_am_i: int = 0x68, takes_writes: bool = True) -> None:
        self.who_am_i = who_am_i
        self.takes_writes = takes_writes  # False: a chip that ignores writes (stays asleep)
        self.regs = bytearray(128)
        self.rate_dps = 0.0
        self.writes: list[tuple[int, bytes]] = []
        self.reset()

    def reset(self) -> None:
        """Power-up values: asleep, every other register 0."""
        for i in range(128):
            self.regs[i] = 0
        self.regs[PWR_MGMT_1] = 0x40
        self.regs[WHO_AM_I] = self.who_am_i

    @property
    def asleep(self) -> bool:
        return bool(self.regs[PWR_MGMT_1] & 0x40)

    def _sample(self) -> None:
        """Latch the rate into GYRO_ZOUT (as the chip's sampling does) unless asleep."""
        if self.asleep:
            return
        fs_sel = (self.regs[GYRO_CONFIG] >> 3) & 3
        v = round(self.rate_dps * LSB_PER_DPS[fs_sel])
        v = 32767 if v > 32767 else (-32768 if v < -32768 else v)
        v &= 0xFFFF
        self.regs[GYRO_ZOUT_H] = v >> 8
        self.regs[GYRO_ZOUT_H + 1] = v & 0xFF

    def read(self, reg: int, n: int) -> bytes:
        self._sample()
        return bytes([self.regs[(reg + k) & 0x7F] for k in range(n)])

    def write(self, reg: int, data: bytes) -> None:
        self.writes.append((reg, bytes(data)))
        if not self.takes_writes:
            return
        for k in range(len(data)):
            r = (reg + k) & 0x7F
            if r == WHO_AM_I or GYRO_OUT <= r < GYRO_OUT + 6:
                continue  # read-only
            if r == PWR_MGMT_1 and data[k] & 0x80:
                self.reset()  # DEVICE_RESET: the bit clears itself
                continue
            self.regs[r] = data[k]


class FakeI2C:
    """A bus with chips at addresses (``devices``: {address: chip})."""

    def __init__(self, devices: "dict[int, FakeMPU6050] | None" = None) -> None:
        self.devices = devices if devices is not None else {}
        self.fail = False

    def _chip(self, addr: int) -> FakeMPU6050:
        chip = self.devices.get(addr)
        if chip is None or self.fail:
            raise OSError(5)  # EIO: no acknowledge
        return chip

    def scan(self) -> "list[int]":
        return sorted(self.devices) if not self.fail else []

    def readfrom_mem(self, addr: int, reg: int, n: int) -> bytes:
        return self._chip(addr).read(reg, n)

    def readfrom_mem_into(self, addr: int, reg: int, buf: bytearray) -> None:
        data = self._chip(addr).read(reg, len(buf))
        for k in range(len(buf)):
            buf[k] = data[k]

    def writeto_mem(self, addr: int, reg: int, data: bytes) -> None:
        self._chip(addr).write(reg, data)
