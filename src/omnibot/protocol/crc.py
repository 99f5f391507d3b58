"""CRC-16/CCITT-FALSE of the binary frames (MicroPython-safe).

Parameters: width 16, polynomial 0x1021, initial value 0xFFFF, no reflection, no final XOR;
check value ``crc16(b"123456789") == 0x29B1``. CPython uses :func:`binascii.crc_hqx` (the same CRC
in C); MicroPython, which lacks it, runs the bitwise loop below.
"""

POLY = 0x1021
INIT = 0xFFFF
CHECK = 0x29B1  # crc16(b"123456789")


def crc16_bitwise(data: bytes, crc: int = INIT) -> int:
    """CRC-16/CCITT-FALSE of ``data``, continuing from ``crc``; one bit at a time."""
    for byte in data:
        crc ^= byte << 8
        for _ in range(8):
            crc = ((crc << 1) ^ POLY) & 0xFFFF if crc & 0x8000 else (crc << 1) & 0xFFFF
    return crc


try:
    from binascii import crc_hqx as _crc_hqx  # type: ignore[attr-defined,unused-ignore]

    def crc16(data: bytes, crc: int = INIT) -> int:
        """CRC-16/CCITT-FALSE of ``data``, continuing from ``crc``."""
        return int(_crc_hqx(data, crc))

except ImportError:  # MicroPython
    crc16 = crc16_bitwise
