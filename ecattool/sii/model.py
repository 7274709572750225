"""The SII EEPROM image model: the fixed area (words 0x00-0x3F) and the category list.

Every byte of a parsed image has a home in this model (reserved words, padding, bytes after the end
marker), so ``parse(image.to_bytes()) == image`` and ``parse(data).to_bytes() == data``.
The writer (:func:`serialize` and the struct layouts of the binary form) lives here beside the model and
the parser in :mod:`ecattool.sii.image`, so that the model never imports its reader.
"""

from __future__ import annotations

import struct
from enum import IntEnum
from typing import ClassVar

from ecattool.errors import InputError
from ecattool.record import Record
from ecattool.sii.crc import preamble_crc


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


class SiiHeader(Record):
    """Words 0x00-0x3F. ``checksum`` is the whole word 7 (low byte = CRC-8)."""

    __slots__ = ("pdi_control", "pdi_config", "sync_impulse_len", "pdi_config2", "station_alias",
                 "reserved_05", "reserved_06", "checksum", "vendor_id", "product_code", "revision", "serial",
                 "reserved_10", "bootstrap_rx_offset", "bootstrap_rx_size", "bootstrap_tx_offset",
                 "bootstrap_tx_size", "std_rx_offset", "std_rx_size", "std_tx_offset", "std_tx_size",
                 "mailbox_protocols", "reserved_1d", "size_word", "version")
    pdi_control: int
    pdi_config: int
    sync_impulse_len: int
    pdi_config2: int
    station_alias: int
    reserved_05: int
    reserved_06: int
    checksum: int
    vendor_id: int
    product_code: int
    revision: int
    serial: int
    reserved_10: bytes
    bootstrap_rx_offset: int
    bootstrap_rx_size: int
    bootstrap_tx_offset: int
    bootstrap_tx_size: int
    std_rx_offset: int
    std_rx_size: int
    std_tx_offset: int
    std_tx_size: int
    mailbox_protocols: int
    reserved_1d: bytes
    size_word: int
    version: int

    def __init__(self, pdi_control: int = 0, pdi_config: int = 0, sync_impulse_len: int = 0,
                 pdi_config2: int = 0, station_alias: int = 0, reserved_05: int = 0, reserved_06: int = 0,
                 checksum: int = 0, vendor_id: int = 0, product_code: int = 0, revision: int = 0,
                 serial: int = 0, reserved_10: bytes = bytes(8), bootstrap_rx_offset: int = 0,
                 bootstrap_rx_size: int = 0, bootstrap_tx_offset: int = 0, bootstrap_tx_size: int = 0,
                 std_rx_offset: int = 0, std_rx_size: int = 0, std_tx_offset: int = 0, std_tx_size: int = 0,
                 mailbox_protocols: int = 0, reserved_1d: bytes = bytes(66), size_word: int = 0,
                 version: int = 1) -> None:
        self.pdi_control = pdi_control
        self.pdi_config = pdi_config
        self.sync_impulse_len = sync_impulse_len
        self.pdi_config2 = pdi_config2
        self.station_alias = station_alias
        self.reserved_05 = reserved_05
        self.reserved_06 = reserved_06
        self.checksum = checksum
        self.vendor_id = vendor_id
        self.product_code = product_code
        self.revision = revision
        self.serial = serial
        self.reserved_10 = reserved_10
        self.bootstrap_rx_offset = bootstrap_rx_offset
        self.bootstrap_rx_size = bootstrap_rx_size
        self.bootstrap_tx_offset = bootstrap_tx_offset
        self.bootstrap_tx_size = bootstrap_tx_size
        self.std_rx_offset = std_rx_offset
        self.std_rx_size = std_rx_size
        self.std_tx_offset = std_tx_offset
        self.std_tx_size = std_tx_size
        self.mailbox_protocols = mailbox_protocols
        self.reserved_1d = reserved_1d
        self.size_word = size_word
        self.version = version

    @property
    def eeprom_bytes(self) -> int:
        """EEPROM size the size word declares: (word + 1) KiBit = (word + 1) * 128 bytes."""
        return (self.size_word + 1) * 128

    @property
    def protocols(self) -> list[str]:
        return [name for name, bit in MAILBOX_PROTOCOLS.items() if self.mailbox_protocols & bit]


class Category(Record):
    """Base of every category. ``extra`` holds body bytes after the typed content (padding included,
    except a single 0x00 that only pads an odd-length content to a whole word)."""

    __slots__ = ()

    TYPE: ClassVar[int] = CategoryType.NOP

    @property
    def cat_type(self) -> int:
        return self.TYPE


class RawCategory(Category):
    """A category kept as bytes: vendor categories, FMMUX, SyncUnit, DataTypes, unknown types, and
    typed categories whose body does not decode (``problem`` says why)."""

    __slots__ = ("type", "data", "problem")
    type: int
    data: bytes
    problem: str

    def __init__(self, type: int = 0, data: bytes = b"", problem: str = "") -> None:
        self.type = type
        self.data = data
        self.problem = problem

    @property
    def cat_type(self) -> int:
        return self.type


class StringsCategory(Category):
    TYPE: ClassVar[int] = CategoryType.STRINGS
    __slots__ = ("strings", "extra")
    strings: list[str]  # Latin-1; index 1 = strings[0]
    extra: bytes

    def __init__(self, strings: list[str] | None = None, extra: bytes = b"") -> None:
        self.strings = [] if strings is None else strings
        self.extra = extra


class GeneralCategory(Category):
    TYPE: ClassVar[int] = CategoryType.GENERAL
    __slots__ = ("group_idx", "image_idx", "order_idx", "name_idx", "physical_layer", "coe_details",
                 "foe_details", "eoe_details", "soe_channels", "ds402_channels", "sysman_class", "flags",
                 "current_on_ebus", "group_name_idx", "reserved_0f", "physical_port",
                 "physical_memory_address", "reserved_14", "extra")
    group_idx: int
    image_idx: int
    order_idx: int
    name_idx: int
    physical_layer: int  # byte 0x04 (reserved in the writers, 2 bits per port in dumps)
    coe_details: int
    foe_details: int
    eoe_details: int
    soe_channels: int
    ds402_channels: int
    sysman_class: int
    flags: int
    current_on_ebus: int  # signed mA; negative = the device feeds the E-bus
    group_name_idx: int  # byte 0x0E
    reserved_0f: int
    physical_port: int  # 4 bits per port: 0 none, 1 MII, 3 EBUS, 4 fast hot connect
    physical_memory_address: int
    reserved_14: bytes
    extra: bytes

    def __init__(self, group_idx: int = 0, image_idx: int = 0, order_idx: int = 0, name_idx: int = 0,
                 physical_layer: int = 0, coe_details: int = 0, foe_details: int = 0, eoe_details: int = 0,
                 soe_channels: int = 0, ds402_channels: int = 0, sysman_class: int = 0, flags: int = 0,
                 current_on_ebus: int = 0, group_name_idx: int = 0, reserved_0f: int = 0,
                 physical_port: int = 0, physical_memory_address: int = 0, reserved_14: bytes = bytes(12),
                 extra: bytes = b"") -> None:
        self.group_idx = group_idx
        self.image_idx = image_idx
        self.order_idx = order_idx
        self.name_idx = name_idx
        self.physical_layer = physical_layer
        self.coe_details = coe_details
        self.foe_details = foe_details
        self.eoe_details = eoe_details
        self.soe_channels = soe_channels
        self.ds402_channels = ds402_channels
        self.sysman_class = sysman_class
        self.flags = flags
        self.current_on_ebus = current_on_ebus
        self.group_name_idx = group_name_idx
        self.reserved_0f = reserved_0f
        self.physical_port = physical_port
        self.physical_memory_address = physical_memory_address
        self.reserved_14 = reserved_14
        self.extra = extra


class FmmuCategory(Category):
    TYPE: ClassVar[int] = CategoryType.FMMU
    __slots__ = ("usages",)
    usages: list[int]  # one byte per FMMU (FMMU_USAGE)

    def __init__(self, usages: list[int] | None = None) -> None:
        self.usages = [] if usages is None else usages


class SiiSyncManager(Record):
    __slots__ = ("start", "length", "control", "status", "enable", "type")
    start: int
    length: int
    control: int
    status: int
    enable: int  # bit0 enable, bit1 fixed content, bit2 virtual, bit3 OP only
    type: int  # SM_TYPES

    def __init__(self, start: int = 0, length: int = 0, control: int = 0, status: int = 0, enable: int = 0,
                 type: int = 0) -> None:
        self.start = start
        self.length = length
        self.control = control
        self.status = status
        self.enable = enable
        self.type = type

    @property
    def kind(self) -> str:
        return SM_TYPES.get(self.type, f"type {self.type}")


class SyncMCategory(Category):
    TYPE: ClassVar[int] = CategoryType.SYNCM
    __slots__ = ("sync_managers", "extra")
    sync_managers: list[SiiSyncManager]
    extra: bytes

    def __init__(self, sync_managers: list[SiiSyncManager] | None = None, extra: bytes = b"") -> None:
        self.sync_managers = [] if sync_managers is None else sync_managers
        self.extra = extra


class SiiPdoEntry(Record):
    __slots__ = ("index", "subindex", "name_idx", "data_type", "bit_len", "flags")
    index: int
    subindex: int
    name_idx: int
    data_type: int
    bit_len: int
    flags: int

    def __init__(self, index: int = 0, subindex: int = 0, name_idx: int = 0, data_type: int = 0,
                 bit_len: int = 0, flags: int = 0) -> None:
        self.index = index
        self.subindex = subindex
        self.name_idx = name_idx
        self.data_type = data_type
        self.bit_len = bit_len
        self.flags = flags


class SiiPdo(Record):
    __slots__ = ("index", "sm", "dc_sync", "name_idx", "flags", "entries")
    index: int
    sm: int
    dc_sync: int
    name_idx: int
    flags: int
    entries: list[SiiPdoEntry]

    def __init__(self, index: int = 0, sm: int = 0, dc_sync: int = 0, name_idx: int = 0, flags: int = 0,
                 entries: list[SiiPdoEntry] | None = None) -> None:
        self.index = index
        self.sm = sm
        self.dc_sync = dc_sync
        self.name_idx = name_idx
        self.flags = flags
        self.entries = [] if entries is None else entries


PDO_FLAGS: dict[str, int] = {"mandatory": 0x0001, "fixed": 0x0010, "virtual": 0x0020, "overwritten_by_module": 0x0080}


class PdoCategory(Category):
    __slots__ = ("type", "pdos", "extra")
    type: int  # 50 TXPDO (inputs) or 51 RXPDO (outputs)
    pdos: list[SiiPdo]
    extra: bytes

    def __init__(self, type: int = CategoryType.TXPDO, pdos: list[SiiPdo] | None = None, extra: bytes = b"") -> None:
        self.type = type
        self.pdos = [] if pdos is None else pdos
        self.extra = extra

    @property
    def cat_type(self) -> int:
        return self.type


class SiiDcOpMode(Record):
    __slots__ = ("cycle_time0", "shift_time0", "shift_time1", "sync1_cycle_factor", "assign_activate",
                 "sync0_cycle_factor", "name_idx", "desc_idx", "reserved")
    cycle_time0: int
    shift_time0: int
    shift_time1: int
    sync1_cycle_factor: int  # signed
    assign_activate: int
    sync0_cycle_factor: int  # signed
    name_idx: int
    desc_idx: int
    reserved: bytes

    def __init__(self, cycle_time0: int = 0, shift_time0: int = 0, shift_time1: int = 0,
                 sync1_cycle_factor: int = 0, assign_activate: int = 0, sync0_cycle_factor: int = 0,
                 name_idx: int = 0, desc_idx: int = 0, reserved: bytes = bytes(4)) -> None:
        self.cycle_time0 = cycle_time0
        self.shift_time0 = shift_time0
        self.shift_time1 = shift_time1
        self.sync1_cycle_factor = sync1_cycle_factor
        self.assign_activate = assign_activate
        self.sync0_cycle_factor = sync0_cycle_factor
        self.name_idx = name_idx
        self.desc_idx = desc_idx
        self.reserved = reserved


class DcCategory(Category):
    TYPE: ClassVar[int] = CategoryType.DC
    __slots__ = ("opmodes", "extra")
    opmodes: list[SiiDcOpMode]
    extra: bytes

    def __init__(self, opmodes: list[SiiDcOpMode] | None = None, extra: bytes = b"") -> None:
        self.opmodes = [] if opmodes is None else opmodes
        self.extra = extra


class SiiImage(Record):
    """A whole image. ``end_marker`` says whether the category list ended with 0xFFFF (False: it ran
    to the end of the data); ``tail`` is every byte after the end marker (usually 0xFF fill)."""

    __slots__ = ("header", "categories", "end_marker", "tail", "source")
    _uncompared = ("source",)
    header: SiiHeader
    categories: list[Category]
    end_marker: bool
    tail: bytes
    source: str

    def __init__(self, header: SiiHeader | None = None, categories: list[Category] | None = None,
                 end_marker: bool = True, tail: bytes = b"", source: str = "") -> None:
        self.header = SiiHeader() if header is None else header
        self.categories = [] if categories is None else categories
        self.end_marker = end_marker
        self.tail = tail
        self.source = source

    # -- convenience ---------------------------------------------------------------------------
    def to_bytes(self) -> bytes:
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
        raw = self.to_bytes()
        return len(raw) >= 15 and raw[14] == preamble_crc(raw)


# ---------------------------------------------------------------------------------------------------
# The binary form: struct layouts and the writer (the parser is ecattool.sii.image)
# ---------------------------------------------------------------------------------------------------
HEADER_BYTES = 128

HEADER_LAYOUT = struct.Struct("<8H4I8s8HH66sHH")  # words 0x00-0x3F
assert HEADER_LAYOUT.size == HEADER_BYTES
GENERAL_LAYOUT = struct.Struct("<12BhBBHH12s")
assert GENERAL_LAYOUT.size == 32
SM_LAYOUT = struct.Struct("<HHBBBB")
PDO_LAYOUT = struct.Struct("<HBBBBH")
ENTRY_LAYOUT = struct.Struct("<HBBBBH")
DC_LAYOUT = struct.Struct("<IIIhHhBB4s")
assert SM_LAYOUT.size == PDO_LAYOUT.size == ENTRY_LAYOUT.size == 8 and DC_LAYOUT.size == 24


def header_bytes(h: SiiHeader) -> bytes:
    try:
        return HEADER_LAYOUT.pack(h.pdi_control, h.pdi_config, h.sync_impulse_len, h.pdi_config2,
                                  h.station_alias, h.reserved_05, h.reserved_06, h.checksum, h.vendor_id,
                                  h.product_code, h.revision, h.serial, h.reserved_10, h.bootstrap_rx_offset,
                                  h.bootstrap_rx_size, h.bootstrap_tx_offset, h.bootstrap_tx_size, h.std_rx_offset,
                                  h.std_rx_size, h.std_tx_offset, h.std_tx_size, h.mailbox_protocols,
                                  h.reserved_1d, h.size_word, h.version)
    except struct.error as exc:
        raise InputError(f"SII header field out of range: {exc}") from None


def strings_content(c: StringsCategory) -> bytes:
    if len(c.strings) > 255:
        raise InputError(f"{len(c.strings)} strings; the STRINGS category holds at most 255")
    out = bytearray([len(c.strings)])
    for s in c.strings:
        try:
            raw = s.encode("latin-1")
        except UnicodeEncodeError:
            raise InputError(f"string {s!r} cannot be written in Latin-1") from None
        if len(raw) > 255:
            raise InputError(f"string {s[:30]!r}… is {len(raw)} bytes; SII strings hold at most 255")
        out += bytes([len(raw)]) + raw
    return bytes(out)


def _general_content(c: GeneralCategory) -> bytes:
    return GENERAL_LAYOUT.pack(c.group_idx, c.image_idx, c.order_idx, c.name_idx, c.physical_layer,
                               c.coe_details, c.foe_details, c.eoe_details, c.soe_channels, c.ds402_channels,
                               c.sysman_class, c.flags, c.current_on_ebus, c.group_name_idx, c.reserved_0f,
                               c.physical_port, c.physical_memory_address, c.reserved_14)


def _pdo_content(c: PdoCategory) -> bytes:
    out = bytearray()
    for p in c.pdos:
        if len(p.entries) > 255:
            raise InputError(f"PDO 0x{p.index:04X} has {len(p.entries)} entries; SII allows 255")
        out += PDO_LAYOUT.pack(p.index, len(p.entries), p.sm, p.dc_sync, p.name_idx, p.flags)
        for e in p.entries:
            out += ENTRY_LAYOUT.pack(e.index, e.subindex, e.name_idx, e.data_type, e.bit_len, e.flags)
    return bytes(out)


def category_body(c: Category) -> bytes:
    """The body bytes of a category, padded to a whole number of words."""
    if isinstance(c, RawCategory):
        body = c.data
    elif isinstance(c, StringsCategory):
        body = strings_content(c) + c.extra
    elif isinstance(c, GeneralCategory):
        body = _general_content(c) + c.extra
    elif isinstance(c, FmmuCategory):
        body = bytes(c.usages)
    elif isinstance(c, SyncMCategory):
        body = b"".join(SM_LAYOUT.pack(s.start, s.length, s.control, s.status, s.enable, s.type)
                        for s in c.sync_managers) + c.extra
    elif isinstance(c, PdoCategory):
        body = _pdo_content(c) + c.extra
    elif isinstance(c, DcCategory):
        body = b"".join(DC_LAYOUT.pack(o.cycle_time0, o.shift_time0, o.shift_time1, o.sync1_cycle_factor,
                                       o.assign_activate, o.sync0_cycle_factor, o.name_idx, o.desc_idx, o.reserved)
                        for o in c.opmodes) + c.extra
    else:  # pragma: no cover - the model has no other kinds
        raise TypeError(type(c).__name__)
    if len(body) % 2:
        body += b"\x00"
    return body


def serialize(image: SiiImage) -> bytes:
    out = bytearray(header_bytes(image.header))
    for c in image.categories:
        try:
            body = category_body(c)
        except struct.error as exc:
            raise InputError(f"{type(c).__name__} field out of range: {exc}") from None
        if len(body) // 2 > 0xFFFF:
            raise InputError(f"category {c.cat_type} is {len(body)} bytes, more than a length word can hold")
        out += struct.pack("<HH", c.cat_type, len(body) // 2) + body
    if image.end_marker:
        out += b"\xff\xff"
    out += image.tail
    return bytes(out)


def fix_crc(image: SiiImage) -> SiiImage:
    """Set the checksum (word 7 low byte) to the CRC of bytes 0-13; the high byte is kept."""
    crc = preamble_crc(header_bytes(image.header))
    image.header.checksum = (image.header.checksum & 0xFF00) | crc
    return image
