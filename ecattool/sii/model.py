"""The SII EEPROM image model: the fixed area (words 0x00-0x3F) and the category list.

Every byte of a parsed image has a home in this model (reserved words, padding, bytes after the end
marker), so ``parse(image.to_bytes()) == image`` and ``parse(data).to_bytes() == data``.
Serialization lives in :mod:`ecattool.sii.image` beside the parser.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import IntEnum
from typing import ClassVar


class CategoryType(IntEnum):
    NOP = 0
    STRINGS = 10
    DATATYPES = 20
    GENERAL = 30
    FMMU = 40
    SYNCM = 41
    FMMUX = 42
    SYNCUNIT = 43
    TXPDO = 50
    RXPDO = 51
    DC = 60
    END = 0xFFFF


def category_name(cat_type: int) -> str:
    try:
        return CategoryType(cat_type).name
    except ValueError:
        if cat_type & 0x8000:
            return f"VENDOR_0x{cat_type:04X}"
        if 1 <= cat_type <= 9:
            return f"DEVICE_SPECIFIC_{cat_type}"
        return f"0x{cat_type:04X}"


#: Mailbox protocol bits of word 0x1C.
MAILBOX_PROTOCOLS: dict[str, int] = {"AoE": 0x01, "EoE": 0x02, "CoE": 0x04, "FoE": 0x08, "SoE": 0x10, "VoE": 0x20}

#: SyncM type byte.
SM_TYPES: dict[int, str] = {0: "", 1: "MBoxOut", 2: "MBoxIn", 3: "Outputs", 4: "Inputs"}

#: FMMU usage byte.
FMMU_USAGE: dict[int, str] = {0: "", 1: "Outputs", 2: "Inputs", 3: "MBoxState", 0xFF: ""}


@dataclass(slots=True)
class SiiHeader:
    """Words 0x00-0x3F. ``checksum`` is the whole word 7 (low byte = CRC-8)."""

    pdi_control: int = 0
    pdi_config: int = 0
    sync_impulse_len: int = 0
    pdi_config2: int = 0
    station_alias: int = 0
    reserved_05: int = 0
    reserved_06: int = 0
    checksum: int = 0
    vendor_id: int = 0
    product_code: int = 0
    revision: int = 0
    serial: int = 0
    reserved_10: bytes = bytes(8)
    bootstrap_rx_offset: int = 0
    bootstrap_rx_size: int = 0
    bootstrap_tx_offset: int = 0
    bootstrap_tx_size: int = 0
    std_rx_offset: int = 0
    std_rx_size: int = 0
    std_tx_offset: int = 0
    std_tx_size: int = 0
    mailbox_protocols: int = 0
    reserved_1d: bytes = bytes(66)
    size_word: int = 0
    version: int = 1

    @property
    def eeprom_bytes(self) -> int:
        """EEPROM size the size word declares: (word + 1) KiBit = (word + 1) * 128 bytes."""
        return (self.size_word + 1) * 128

    @property
    def protocols(self) -> list[str]:
        return [name for name, bit in MAILBOX_PROTOCOLS.items() if self.mailbox_protocols & bit]


@dataclass(slots=True)
class Category:
    """Base of every category. ``extra`` holds body bytes after the typed content (padding included,
    except a single 0x00 that only pads an odd-length content to a whole word)."""

    TYPE: ClassVar[int] = CategoryType.NOP

    @property
    def cat_type(self) -> int:
        return self.TYPE


@dataclass(slots=True)
class RawCategory(Category):
    """A category kept as bytes: vendor categories, FMMUX, SyncUnit, DataTypes, unknown types, and
    typed categories whose body does not decode (``problem`` says why)."""

    type: int = 0
    data: bytes = b""
    problem: str = ""

    @property
    def cat_type(self) -> int:
        return self.type


@dataclass(slots=True)
class StringsCategory(Category):
    TYPE: ClassVar[int] = CategoryType.STRINGS
    strings: list[str] = field(default_factory=list)  # Latin-1; index 1 = strings[0]
    extra: bytes = b""


@dataclass(slots=True)
class GeneralCategory(Category):
    TYPE: ClassVar[int] = CategoryType.GENERAL
    group_idx: int = 0
    image_idx: int = 0
    order_idx: int = 0
    name_idx: int = 0
    physical_layer: int = 0  # byte 0x04 (reserved in the writers, 2 bits per port in dumps)
    coe_details: int = 0
    foe_details: int = 0
    eoe_details: int = 0
    soe_channels: int = 0
    ds402_channels: int = 0
    sysman_class: int = 0
    flags: int = 0
    current_on_ebus: int = 0  # signed mA; negative = the device feeds the E-bus
    group_name_idx: int = 0  # byte 0x0E
    reserved_0f: int = 0
    physical_port: int = 0  # 4 bits per port: 0 none, 1 MII, 3 EBUS, 4 fast hot connect
    physical_memory_address: int = 0
    reserved_14: bytes = bytes(12)
    extra: bytes = b""


@dataclass(slots=True)
class FmmuCategory(Category):
    TYPE: ClassVar[int] = CategoryType.FMMU
    usages: list[int] = field(default_factory=list)  # one byte per FMMU (FMMU_USAGE)


@dataclass(slots=True)
class SiiSyncManager:
    start: int = 0
    length: int = 0
    control: int = 0
    status: int = 0
    enable: int = 0  # bit0 enable, bit1 fixed content, bit2 virtual, bit3 OP only
    type: int = 0  # SM_TYPES

    @property
    def kind(self) -> str:
        return SM_TYPES.get(self.type, f"type {self.type}")


@dataclass(slots=True)
class SyncMCategory(Category):
    TYPE: ClassVar[int] = CategoryType.SYNCM
    sync_managers: list[SiiSyncManager] = field(default_factory=list)
    extra: bytes = b""


@dataclass(slots=True)
class SiiPdoEntry:
    index: int = 0
    subindex: int = 0
    name_idx: int = 0
    data_type: int = 0
    bit_len: int = 0
    flags: int = 0


@dataclass(slots=True)
class SiiPdo:
    index: int = 0
    sm: int = 0
    dc_sync: int = 0
    name_idx: int = 0
    flags: int = 0
    entries: list[SiiPdoEntry] = field(default_factory=list)


PDO_FLAGS: dict[str, int] = {"mandatory": 0x0001, "fixed": 0x0010, "virtual": 0x0020, "overwritten_by_module": 0x0080}


@dataclass(slots=True)
class PdoCategory(Category):
    type: int = CategoryType.TXPDO  # 50 TXPDO (inputs) or 51 RXPDO (outputs)
    pdos: list[SiiPdo] = field(default_factory=list)
    extra: bytes = b""

    @property
    def cat_type(self) -> int:
        return self.type


@dataclass(slots=True)
class SiiDcOpMode:
    cycle_time0: int = 0
    shift_time0: int = 0
    shift_time1: int = 0
    sync1_cycle_factor: int = 0  # signed
    assign_activate: int = 0
    sync0_cycle_factor: int = 0  # signed
    name_idx: int = 0
    desc_idx: int = 0
    reserved: bytes = bytes(4)


@dataclass(slots=True)
class DcCategory(Category):
    TYPE: ClassVar[int] = CategoryType.DC
    opmodes: list[SiiDcOpMode] = field(default_factory=list)
    extra: bytes = b""


@dataclass(slots=True)
class SiiImage:
    """A whole image. ``end_marker`` says whether the category list ended with 0xFFFF (False: it ran
    to the end of the data); ``tail`` is every byte after the end marker (usually 0xFF fill)."""

    header: SiiHeader = field(default_factory=SiiHeader)
    categories: list[Category] = field(default_factory=list)
    end_marker: bool = True
    tail: bytes = b""
    source: str = field(default="", compare=False)

    # -- convenience ---------------------------------------------------------------------------
    def to_bytes(self) -> bytes:
        from ecattool.sii.image import serialize

        return serialize(self)

    def first(self, cat_cls: type, cat_type: int | None = None) -> Category | None:
        for c in self.categories:
            if isinstance(c, cat_cls) and (cat_type is None or c.cat_type == cat_type):
                return c
        return None

    @property
    def strings(self) -> list[str]:
        c = self.first(StringsCategory)
        return list(c.strings) if isinstance(c, StringsCategory) else []

    def string(self, idx: int) -> str | None:
        """1-based string reference; 0 = none (returns ""); None when out of range."""
        if idx == 0:
            return ""
        s = self.strings
        return s[idx - 1] if 0 < idx <= len(s) else None

    @property
    def general(self) -> GeneralCategory | None:
        c = self.first(GeneralCategory)
        return c if isinstance(c, GeneralCategory) else None

    @property
    def fmmus(self) -> list[int]:
        return [u for c in self.categories if isinstance(c, FmmuCategory) for u in c.usages]

    @property
    def sync_managers(self) -> list[SiiSyncManager]:
        return [s for c in self.categories if isinstance(c, SyncMCategory) for s in c.sync_managers]

    def pdos(self, cat_type: int) -> list[SiiPdo]:
        return [p for c in self.categories if isinstance(c, PdoCategory) and c.type == cat_type for p in c.pdos]

    @property
    def tx_pdos(self) -> list[SiiPdo]:
        return self.pdos(CategoryType.TXPDO)

    @property
    def rx_pdos(self) -> list[SiiPdo]:
        return self.pdos(CategoryType.RXPDO)

    @property
    def dc_opmodes(self) -> list[SiiDcOpMode]:
        return [o for c in self.categories if isinstance(c, DcCategory) for o in c.opmodes]

    @property
    def crc_ok(self) -> bool:
        from ecattool.sii.crc import preamble_crc

        raw = self.to_bytes()
        return len(raw) >= 15 and raw[14] == preamble_crc(raw)
