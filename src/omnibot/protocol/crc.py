"""CRC-32 of the binary frames (MicroPython-safe).

CRC-32/ISO-HDLC, the CRC of Ethernet, zip and PNG: polynomial 0x04C11DB7 (0xEDB88320 reflected),
initial value and final XOR 0xFFFFFFFF, reflected in and out; check value
``crc32(b"123456789") == 0xCBF43926``. CPython and MicroPython both have it in C as
:func:`binascii.crc32`; a MicroPython built without it runs the bitwise loop below.

Its Hamming distance (Koopman's CRC tables, polynomial 0x82608edb in his notation) is 6 up to 268
data bits, 5 up to 2974 bits and 4 up to 91607 bits: a frame's checked bytes are at most 250
(2000 bits), so every error of 1 to 4 bits in them is detected, as is every burst of up to 32 bits
and any other error but 1 in 2^32.
"""

POLY = 0xEDB88320  # 0x04C11DB7 bit-reversed
CHECK = 0xCBF43926  # crc32(b"123456789")
_MASK = 0xFFFFFFFF


def crc32_bitwise(data: bytes, crc: int = 0) -> int:
    """CRC-32 of ``data``, continuing from the CRC ``crc`` of earlier bytes; one bit at a time."""
    crc ^= _MASK
    for byte in data:
        crc ^= byte
        for _ in range(8):
            crc = (crc >> 1) ^ POLY if crc & 1 else crc >> 1
    return crc ^ _MASK


try:
    from binascii import crc32 as _crc32  # type: ignore[attr-defined,unused-ignore]

    def crc32(data: bytes, crc: int = 0) -> int:
        """CRC-32 of ``data``, continuing from the CRC ``crc`` of earlier bytes."""
        return int(_crc32(data, crc)) & _MASK

except ImportError:  # a MicroPython port built without binascii.crc32
    crc32 = crc32_bitwise
