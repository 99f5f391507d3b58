"""The MPU6050's yaw-rate gyro over I2C (seed 002's part), for MachineHAL; MicroPython subset.

The chip is read through any object with MicroPython's ``machine.I2C`` memory calls
(``readfrom_mem``, ``readfrom_mem_into``, ``writeto_mem``); tests hand it a register-level model
(tests/firmware/fake_mpu6050.py). Registers used (InvenSense RM-MPU-6000A, register map rev. 4.2)::

    0x19 SMPLRT_DIV    sample rate = gyro output rate / (1 + SMPLRT_DIV); 1 kHz with the DLPF on
    0x1A CONFIG        bits 2:0 DLPF_CFG: 0 256 Hz (DLPF off, 8 kHz), 1 188, 2 98, 3 42, 4 20, 5 10, 6 5 Hz
    0x1B GYRO_CONFIG   bits 4:3 FS_SEL: +-250, 500, 1000, 2000 deg/s = 131, 65.5, 32.8, 16.4 LSB per deg/s
    0x47 GYRO_ZOUT_H   yaw rate, big-endian two's complement, with 0x48 GYRO_ZOUT_L
    0x6B PWR_MGMT_1    bit 7 DEVICE_RESET, bit 6 SLEEP (set at power-up), bits 2:0 CLKSEL (1: X gyro PLL)
    0x75 WHO_AM_I      0x68 whichever address AD0 picks (0x68 low, 0x69 high)

Boot: WHO_AM_I must read 0x68; then wake (CLKSEL 1, SLEEP 0), sample divider, DLPF, range, and read
PWR_MGMT_1 and GYRO_CONFIG back. Any failure raises :class:`GyroError` with what was wrong, so the
board can report "no gyro" and run on without it. The bias is left to the host (estimation/gyro_bias).
"""

SMPLRT_DIV = 0x19
CONFIG = 0x1A
GYRO_CONFIG = 0x1B
GYRO_ZOUT_H = 0x47
PWR_MGMT_1 = 0x6B
WHO_AM_I = 0x75

ADDRESSES = (0x68, 0x69)
CHIP_ID = 0x68
SLEEP = 0x40
CLKSEL_PLL_X = 0x01
FULL_SCALE_DPS = (250, 500, 1000, 2000)
LSB_PER_DPS_X10 = (1310, 655, 328, 164)  # sensitivity of each FS_SEL, 0.1 LSB per deg/s
DLPF_HZ = (256, 188, 98, 42, 20, 10, 5)  # DLPF_CFG 0..6


class GyroError(Exception):
    """The MPU6050 is absent, is not an MPU6050, or did not take its settings."""


def fs_sel_for(range_dps: float) -> int:
    """The smallest FS_SEL whose full scale covers ``range_dps``; ValueError beyond +-2000 deg/s."""
    for k in range(len(FULL_SCALE_DPS)):
        if range_dps <= FULL_SCALE_DPS[k] * 1.0001:
            return k
    raise ValueError("an MPU6050 measures up to 2000 deg/s")


def dlpf_cfg_for(bandwidth_hz: float) -> int:
    """The DLPF_CFG of the narrowest bandwidth that still passes ``bandwidth_hz``."""
    best = 0
    for k in range(len(DLPF_HZ)):
        if DLPF_HZ[k] >= bandwidth_hz:
            best = k
    return best


def _reason(exc: OSError) -> str:
    """An I2C failure's errno, spelt alike in MicroPython and CPython (5 EIO: no acknowledge)."""
    return "errno " + (str(exc.args[0]) if exc.args else "?")


class MPU6050:
    """One MPU6050 on ``i2c`` at ``address``: woken and set up at construction (GyroError if it
    cannot be), then :meth:`rate_mdps` reads the yaw rate."""

    def __init__(
        self, i2c: "Any", address: int = 0x68, fs_sel: int = 0, dlpf_cfg: int = 3, sample_div: int = 0
    ) -> None:
        if address not in ADDRESSES:
            raise GyroError(
                f"MPU6050 address 0x{address:02x}: it answers at 0x68 (AD0 low) or 0x69 (AD0 high)"
            )
        self._i2c = i2c
        self.address = address
        self.fs_sel = fs_sel & 3
        self._lsb_x10 = LSB_PER_DPS_X10[self.fs_sel]
        self._buf = bytearray(2)
        try:
            who = i2c.readfrom_mem(address, WHO_AM_I, 1)[0]
        except OSError as exc:
            why = _reason(exc)
            raise GyroError(
                f"no MPU6050 answers at 0x{address:02x} on I2C ({why}): check SDA, SCL, 3.3 V and AD0"
            ) from None
        if who != CHIP_ID:
            raise GyroError(f"the chip at 0x{address:02x} says WHO_AM_I 0x{who:02x}, not an MPU6050's 0x68")
        try:
            i2c.writeto_mem(address, PWR_MGMT_1, bytes([CLKSEL_PLL_X]))  # wake, gyro X PLL clock
            i2c.writeto_mem(address, SMPLRT_DIV, bytes([sample_div & 0xFF]))
            i2c.writeto_mem(address, CONFIG, bytes([dlpf_cfg & 7]))
            i2c.writeto_mem(address, GYRO_CONFIG, bytes([self.fs_sel << 3]))
            power = i2c.readfrom_mem(address, PWR_MGMT_1, 1)[0]
            scale = i2c.readfrom_mem(address, GYRO_CONFIG, 1)[0]
        except OSError as exc:
            why = _reason(exc)
            raise GyroError(
                f"the MPU6050 at 0x{address:02x} stopped answering while being set up ({why})"
            ) from None
        if power & SLEEP or (scale >> 3) & 3 != self.fs_sel:
            raise GyroError(
                f"the MPU6050 at 0x{address:02x} did not take its settings (PWR_MGMT_1 0x{power:02x})"
            )

    def raw(self) -> int:
        """GYRO_ZOUT as a signed 16-bit count (OSError when the bus fails)."""
        buf = self._buf
        self._i2c.readfrom_mem_into(self.address, GYRO_ZOUT_H, buf)
        v = (buf[0] << 8) | buf[1]
        return v - 65536 if v >= 32768 else v

    def rate_mdps(self) -> int:
        """The yaw rate in millidegrees/s (counter-clockwise seen from above, chip face up: positive),
        rounded towards zero (OSError when the bus fails)."""
        v = self.raw()
        if v < 0:
            return -((-v * 10000) // self._lsb_x10)
        return (v * 10000) // self._lsb_x10


TYPE_CHECKING = False
if TYPE_CHECKING:
    from typing import Any
