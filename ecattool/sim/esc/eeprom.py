"""The SII EEPROM behind the ESC's EEPROM interface (0x0500-0x050F): word addressed, read 4 or 8 bytes at a
time, written one word at a time with the write enable bit, reloaded into the ESC configuration area."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from ecattool.sii.crc import crc8
from ecattool.sim.esc import registers as R


@dataclass(frozen=True, slots=True)
class Result:
    data: bytes | None = None
    error: bool = False
    busy: bool = False


class SiiEeprom:
    """The EEPROM words of an SII image. ``busy_reads``: how many status reads a command stays busy (a real
    EEPROM needs some microseconds; masters poll the busy bit). ``write_hook(address, word)`` runs before a
    word is stored (fault injection raises from it to lose the write)."""

    def __init__(self, image: bytes, *, read_8: bool = True, busy_reads: int = 1,
                 write_hook: Callable[[int, int], None] | None = None) -> None:
        raw = bytes(image) + (b"\xff" if len(image) % 2 else b"")
        self.data = bytearray(raw or b"\xff" * 128)
        self.read_8 = read_8
        self.busy_reads = busy_reads
        self.write_hook = write_hook
        self._busy = 0
        self._errors = 0

    @property
    def size_words(self) -> int:
        return len(self.data) // 2

    def words(self, start: int, count: int) -> list[int]:
        return [int.from_bytes(self.data[2 * a:2 * a + 2], "little") if a < self.size_words else 0xFFFF
                for a in range(start, start + count)]

    @property
    def busy(self) -> bool:
        return self._busy > 0

    def tick(self) -> None:
        self._busy = max(0, self._busy - 1)

    def status_bits(self) -> int:
        bits = (R.EE_READ_8 if self.read_8 else 0) | R.EE_TWO_ADDRESS_BYTES | self._errors
        return bits | (R.EE_BUSY if self._busy else 0)

    def checksum_ok(self) -> bool:
        return len(self.data) >= 16 and crc8(bytes(self.data[:14])) == self.data[14]

    def command(self, cmd: int, write_enable: bool, address: int, word: int) -> Result:
        """Run one command written to 0x0502 (cmd = bits 8..10)."""
        if cmd == 0:
            return Result()
        if self._busy:
            # a command while busy is not taken (the master must poll first)
            self._errors |= R.EE_ACK_ERROR
            return Result(error=True)
        self._errors = 0
        self._busy = self.busy_reads
        if cmd == R.EE_CMD_READ:
            if address >= self.size_words:
                self._errors |= R.EE_ACK_ERROR
                return Result(error=True, busy=bool(self._busy))
            n = 8 if self.read_8 else 4
            chunk = bytes(self.data[2 * address:2 * address + n]).ljust(n, b"\xff")
            return Result(data=chunk, busy=bool(self._busy))
        if cmd == R.EE_CMD_WRITE:
            if not write_enable:
                self._errors |= R.EE_WRITE_ERROR
                return Result(error=True, busy=bool(self._busy))
            if address >= self.size_words:
                self._errors |= R.EE_ACK_ERROR
                return Result(error=True, busy=bool(self._busy))
            if self.write_hook is not None:
                self.write_hook(address, word)
            self.data[2 * address:2 * address + 2] = word.to_bytes(2, "little")
            return Result(busy=bool(self._busy))
        if cmd == R.EE_CMD_RELOAD:
            if not self.checksum_ok():
                self._errors |= R.EE_CHECKSUM_ERROR | R.EE_LOAD_ERROR
                return Result(error=True, busy=bool(self._busy))
            return Result(busy=bool(self._busy))
        self._errors |= R.EE_ACK_ERROR
        return Result(error=True, busy=bool(self._busy))
