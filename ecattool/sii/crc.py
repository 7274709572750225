"""The SII preamble checksum: CRC-8, polynomial x^8+x^2+x+1 (0x07), initial value 0xFF, MSB first,
no reflection, no final XOR, over bytes 0..13 of the image; the result is stored in byte 14 (word 7 low)."""

from __future__ import annotations


def _table() -> tuple[int, ...]:
    out = []
    for byte in range(256):
        crc = byte
        for _ in range(8):
            crc = ((crc << 1) ^ 0x07) & 0xFF if crc & 0x80 else (crc << 1) & 0xFF
        out.append(crc)
    return tuple(out)


_TABLE = _table()


def crc8(data: bytes, init: int = 0xFF) -> int:
    """CRC-8/0x07 with initial value ``init`` (0xFF for SII). ``crc8(b"123456789") == 0xFB``."""
    crc = init
    for b in data:
        crc = _TABLE[crc ^ b]
    return crc


def preamble_crc(image: bytes) -> int:
    """The checksum the first 14 bytes of ``image`` call for."""
    return crc8(bytes(image[:14]))
