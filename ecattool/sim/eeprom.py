"""The Technosoft iPOS memory behind 2064h/2065h/2066h/2067h, checksum 2069h/206Ah, lock 2091h, FoE rules.

Word-addressed 16-bit memories (program 00b, data 01b, EEPROM 10b in 2064h bits 3..2). 2064h layout:
bits 31..16 address, bit 7 = 1 no auto-increment (0 = auto-increment), bits 3..2 memory type, bit 0 =
32-bit access. Auto-increment adds 1 per 16-bit access and 2 per 32-bit access (§17.4.1 example), reads
of 2066h advance the address too. The checksum is the 16-bit sum of EEPROM words start..end inclusive.
The EEPROM keeps its contents across resets and power loss; data and program memory do not.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field

PROGRAM, DATA, EEPROM = 0, 1, 2
BLANK = 0xFFFF

#: FoE error codes (ETG.1000.6)
FOE_NOT_DEFINED = 0x8000
FOE_NOT_FOUND = 0x8001
FOE_ACCESS_DENIED = 0x8002
FOE_ILLEGAL = 0x8004
FOE_BOOTSTRAP_ONLY = 0x8008
FOE_NOT_BOOTSTRAP = 0x8009
FOE_NO_RIGHTS = 0x800A

#: firmware FoE passwords (§17.4.6): F515x "515F", FA0xx "A00A"
FIRMWARE_PASSWORDS = (0x35313546, 0x41303041)

_SETUP_NAME = re.compile(r"^(FOESW_[^.]*)(\.(bin|efw))?$")
_FIRMWARE_NAME = re.compile(r"^FOEFW_")


class EepromLocked(Exception):
    """Raised by :class:`Memory` when an EEPROM write hits a locked EEPROM (2091h bit 0)."""


class PowerLost(Exception):
    """Raised by :class:`Memory` when fault injection cuts the power during an EEPROM write."""


@dataclass
class Memory:
    config: int = 0x84  # 2064h default: address 0, no auto-increment, data memory, 16-bit
    locked: bool = False
    checksum: int = 0
    eeprom: dict[int, int] = field(default_factory=dict)
    ram: dict[int, dict[int, int]] = field(default_factory=lambda: {PROGRAM: {}, DATA: {}})
    #: fault injection: the EEPROM loses power when this many more words have been written (None = never)
    power_loss_after: int | None = None
    words_written: int = 0

    # --- 2064h -------------------------------------------------------------------------------
    @property
    def address(self) -> int:
        return (self.config >> 16) & 0xFFFF

    @property
    def memory_type(self) -> int:
        return (self.config >> 2) & 0x3

    @property
    def wide(self) -> bool:
        return bool(self.config & 0x1)

    @property
    def auto_increment(self) -> bool:
        return not self.config & 0x80

    def _advance(self, words: int) -> None:
        if self.auto_increment:
            self.config = (((self.address + words) & 0xFFFF) << 16) | (self.config & 0xFFFF)

    # --- words ---------------------------------------------------------------------------------
    def read_word(self, mem: int, address: int) -> int:
        address &= 0xFFFF
        if mem == EEPROM:
            return self.eeprom.get(address, BLANK)
        return self.ram.setdefault(mem, {}).get(address, 0)

    def write_word(self, mem: int, address: int, value: int) -> None:
        address &= 0xFFFF
        if mem == EEPROM:
            if self.locked:
                raise EepromLocked()
            if self.power_loss_after is not None:
                if self.power_loss_after <= 0:
                    self.power_loss_after = None
                    raise PowerLost()
                self.power_loss_after -= 1
            self.eeprom[address] = value & 0xFFFF
            self.words_written += 1
        else:
            self.ram.setdefault(mem, {})[address] = value & 0xFFFF

    # --- the objects ------------------------------------------------------------------------------
    def write_2065(self, value: int) -> None:
        mem, addr = self.memory_type, self.address
        if self.wide:
            self.write_word(mem, addr, value & 0xFFFF)
            self.write_word(mem, addr + 1, value >> 16)
            self._advance(2)
        else:
            self.write_word(mem, addr, value & 0xFFFF)  # high word ignored in 16-bit mode
            self._advance(1)

    def read_2066(self) -> int:
        mem, addr = self.memory_type, self.address
        if self.wide:
            value = self.read_word(mem, addr) | (self.read_word(mem, addr + 1) << 16)
            self._advance(2)
        else:
            value = self.read_word(mem, addr)
            self._advance(1)
        return value

    def write_2067(self, value: int) -> None:
        self.write_word(self.memory_type, value >> 16, value & 0xFFFF)

    def compute_checksum(self, value: int) -> int:
        """2069h write: sum of EEPROM words start (low word) .. end (high word), both inclusive."""
        start, end = value & 0xFFFF, value >> 16
        total = 0
        for a in range(start, end + 1):
            total += self.read_word(EEPROM, a)
        self.checksum = total & 0xFFFF
        return self.checksum

    def reset(self) -> None:
        """Drive reset / power cycle: registers and RAM are lost, the EEPROM keeps its contents."""
        self.config = 0x84
        self.checksum = 0
        self.ram = {PROGRAM: {}, DATA: {}}


def parse_foe_setup(data: bytes) -> list[tuple[int, list[int]]]:
    """A ``FOESW_*.bin`` image: blocks of [start u16 LE][count u16 LE][count × u16 LE], nothing else.

    Raises ValueError when the image is truncated.
    """
    blocks: list[tuple[int, list[int]]] = []
    pos = 0
    while pos < len(data):
        if pos + 4 > len(data):
            raise ValueError(f"truncated block header at byte {pos}")
        start = int.from_bytes(data[pos:pos + 2], "little")
        count = int.from_bytes(data[pos + 2:pos + 4], "little")
        pos += 4
        end = pos + 2 * count
        if end > len(data):
            raise ValueError(f"block at 0x{start:04X} announces {count} words but the image ends")
        blocks.append((start, [int.from_bytes(data[i:i + 2], "little") for i in range(pos, end, 2)]))
        pos = end
    return blocks


def check_setup_name(name: str) -> str | None:
    """Why a setup-file FoE name is rejected (§17.4.3.1), or None when it is acceptable."""
    m = _SETUP_NAME.match(name)
    if not m:
        return "a setup file name must start with FOESW_ (and end in .bin/.efw if it has an extension)"
    if len(m.group(1)) > 14:
        return f"{m.group(1)!r} is {len(m.group(1))} characters; at most 14 without the extension"
    return None


def is_firmware_name(name: str) -> bool:
    return bool(_FIRMWARE_NAME.match(name))
