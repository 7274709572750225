"""Build an SII image from a device model (an ESI device or a built-in profile).

Where the generators in use disagree, the builder follows real device dumps (NI 9144, Beckhoff and
Kollmorgen dumps quoted in the field notes); every such choice is listed in docs/decisions.md
("SII images") and pinned by a named test in tests/sii/test_sii_build.py.
"""

from __future__ import annotations

from ecattool.errors import InputError, Location
from ecattool.esi.model import Device, Pdo, SyncManager
from ecattool.od.types import lookup
from ecattool.sii.image import parse, parse_category
from ecattool.sii.model import (
    HEADER_BYTES,
    MAILBOX_PROTOCOLS,
    PDO_FLAGS,
    Category,
    CategoryType,
    DcCategory,
    FmmuCategory,
    GeneralCategory,
    PdoCategory,
    RawCategory,
    SiiDcOpMode,
    SiiHeader,
    SiiImage,
    SiiPdo,
    SiiPdoEntry,
    SiiSyncManager,
    StringsCategory,
    SyncMCategory,
    category_body,
    fix_crc,
    strings_content,
)

SM_TYPE_CODES = {"MBoxOut": 1, "MBoxIn": 2, "Outputs": 3, "Inputs": 4}
FMMU_CODES = {"Outputs": 1, "Inputs": 2, "MBoxState": 3}
PORT_CODES = {"Y": 1, "K": 3, "H": 4}
#: Bit-string types written as the unsigned type of the same width, as the NI 9144 dump does (WORD → 6).
BITSTRING_AS_UNSIGNED = {"BYTE": 0x05, "WORD": 0x06, "DWORD": 0x07}
DEFAULT_EEPROM_BYTES = 2048


class StringTable:
    """The STRINGS category being built: Latin-1, 1-based, duplicates share one index, "" is 0."""

    def __init__(self) -> None:
        self.strings: list[str] = []
        self._index: dict[str, int] = {}

    def add(self, text: str | None) -> int:
        if not text:
            return 0
        text = text[:255]
        try:
            text.encode("latin-1")
        except UnicodeEncodeError:
            text = text.encode("latin-1", "replace").decode("latin-1")
        idx = self._index.get(text)
        if idx is None:
            if len(self.strings) >= 255:
                raise InputError(f"more than 255 distinct strings; cannot add {text[:30]!r} to the STRINGS category")
            self.strings.append(text)
            idx = self._index[text] = len(self.strings)
        return idx


def data_type_code(name: str) -> int:
    """The SII entry data-type byte for an ESI type name (0 when not a standard type)."""
    key = name.strip().upper()
    if key in BITSTRING_AS_UNSIGNED:
        return BITSTRING_AS_UNSIGNED[key]
    dt = lookup(key) if key else None
    return dt.code & 0xFF if dt is not None and dt.code <= 0xFF else 0


def physical_port(physics: str) -> int:
    word = 0
    for i, ch in enumerate(physics[:4]):
        word |= PORT_CODES.get(ch.upper(), 0) << (4 * i)
    return word


def _u32(v: int | None) -> int:
    return (v or 0) & 0xFFFFFFFF


def _enable_byte(sm: SyncManager) -> int:
    """The SII SyncM enable byte: ``Sm@Enable`` as the ESI gives it (bit 0 enable, bit 1 fixed content, bit 2
    virtual, bit 3 OP only), with the bits that ``Sm@Virtual`` and ``Sm@OpOnly`` state; without an ``Enable``
    attribute, 1 (enabled)."""
    given = sm.enable_byte if sm.enable_byte is not None else (1 if sm.enable else 0)
    return given | (4 if sm.virtual else 0) | (8 if sm.op_only else 0)


def _pdo(device: Device, p: Pdo, strings: StringTable) -> SiiPdo:
    """The PDO category entry of ``p`` with the entries the slave powers on with: where the ESI's dictionary gives
    the mapping object another default than the PDO element, the dictionary's (``esi.power_on``)."""
    from ecattool.esi.power_on import power_on_entries

    flags = 0
    for name, bit in PDO_FLAGS.items():
        if getattr(p, name, False):
            flags |= bit
    name_idx = strings.add(p.name)  # the PDO name comes before its entries' names, as in the dumps
    entries = [SiiPdoEntry(e.index, e.subindex, strings.add(e.name), data_type_code(e.data_type),
                           e.bit_len & 0xFF, 0) for e in power_on_entries(device, p)]
    return SiiPdo(p.index, 0xFF if p.sm is None else p.sm, 0, name_idx, flags, entries)


def size_word_for(byte_size: int, where: Location | None = None) -> int:
    if byte_size < HEADER_BYTES or byte_size % 128 or byte_size // 128 > 0x10000:
        raise InputError(f"EEPROM size {byte_size} bytes is not a multiple of 128 between 128 and 8 MiB", where)
    return byte_size // 128 - 1


def build(device: Device, *, pdo_categories: bool = True, size: int | None = None) -> SiiImage:
    """Build the image ``device`` describes, filled with 0xFF to the EEPROM size.

    ``size`` (bytes) overrides ``Eeprom/ByteSize``; without either the image is 2048 bytes, or the next
    power of two that holds it. A raw ``Eeprom/Data`` image is returned as it is.
    """
    where = device.location or Location(device.source or None)
    eeprom = device.eeprom
    if eeprom is not None and eeprom.data:
        image = parse(eeprom.data, device.source or None)
        image.source = device.source
        return image
    image = assemble(device, pdo_categories=pdo_categories)
    used = len(image.to_bytes())
    byte_size = size if size is not None else (eeprom.byte_size if eeprom and eeprom.byte_size else None)
    if byte_size is None:
        byte_size = DEFAULT_EEPROM_BYTES
        while byte_size < used:
            byte_size *= 2
    image.header.size_word = size_word_for(byte_size, where)
    if used > byte_size:
        raise InputError(f"the image needs {used} bytes but the EEPROM holds {byte_size}; use --size or "
                         "--no-pdo-categories", where)
    image.tail = b"\xff" * (byte_size - used)
    return fix_crc(image)


def assemble(device: Device, *, pdo_categories: bool = True) -> SiiImage:
    """The fixed area and categories of ``device`` (no fill, size word from ByteSize, CRC not set)."""
    eeprom = device.eeprom

    h = SiiHeader()
    cfg = (eeprom.config_data if eeprom and eeprom.config_data else b"")[:14].ljust(14, b"\x00")
    (h.pdi_control, h.pdi_config, h.sync_impulse_len, h.pdi_config2, h.station_alias, h.reserved_05,
     h.reserved_06) = (int.from_bytes(cfg[i:i + 2], "little") for i in range(0, 14, 2))
    ident = device.identity
    h.vendor_id, h.product_code = ident.vendor_id & 0xFFFFFFFF, ident.product_code & 0xFFFFFFFF
    h.revision, h.serial = ident.revision & 0xFFFFFFFF, ident.serial & 0xFFFFFFFF
    if eeprom and eeprom.bootstrap:
        boot = eeprom.bootstrap[:8].ljust(8, b"\x00")
        (h.bootstrap_rx_offset, h.bootstrap_rx_size, h.bootstrap_tx_offset,
         h.bootstrap_tx_size) = (int.from_bytes(boot[i:i + 2], "little") for i in range(0, 8, 2))
    for sm in device.sync_managers:
        if sm.kind == "MBoxOut" and not h.std_rx_size:
            h.std_rx_offset, h.std_rx_size = sm.start_address, sm.default_size or 0
        elif sm.kind == "MBoxIn" and not h.std_tx_size:
            h.std_tx_offset, h.std_tx_size = sm.start_address, sm.default_size or 0
    mbx = device.mailbox
    protocols = mbx.protocols if mbx else []
    for p in protocols:
        h.mailbox_protocols |= MAILBOX_PROTOCOLS.get(p, 0)

    strings = StringTable()
    general = GeneralCategory()
    general.order_idx = strings.add(device.type_name)
    general.group_idx = strings.add(device.group_type)
    general.group_name_idx = strings.add(device.group_name)
    general.name_idx = strings.add(device.name or device.type_name)
    if "CoE" in protocols:
        coe = mbx.coe if mbx else None
        general.coe_details = 0x01
        if coe is not None:
            for bit, on in ((0x02, coe.sdo_info), (0x04, coe.pdo_assign), (0x08, coe.pdo_config),
                            (0x10, coe.pdo_upload), (0x20, coe.complete_access)):
                if on:
                    general.coe_details |= bit
    general.foe_details = 1 if "FoE" in protocols else 0
    general.eoe_details = 1 if "EoE" in protocols else 0
    general.flags = 0x04 if mbx is not None and mbx.data_link_layer else 0
    general.current_on_ebus = max(-0x8000, min(0x7FFF, device.ebus_current_ma or 0))
    general.physical_port = physical_port(device.physics)

    dc_ops = [SiiDcOpMode(_u32(o.cycle_time_sync0), _u32(o.shift_time_sync0), _u32(o.shift_time_sync1),
                          o.cycle_time_sync1_factor or 0, o.assign_activate & 0xFFFF,
                          1 if o.cycle_time_sync0_factor is None else o.cycle_time_sync0_factor,
                          strings.add(o.name), 0)
              for o in device.dc_opmodes]
    # a virtual PDO that is a window onto ESC registers (Device.esc_registers, docs/esi.md "Virtual PDOs") is no
    # PDO of a sync manager: a master without CoE lays out its SMs from these categories (SOEM's config_map sums
    # every PDO with an SM number), so listing it would lay out an image the slave's mapping does not have
    tx = [_pdo(device, p, strings) for p in device.tx_pdos if not device.esc_registers(p)] if pdo_categories else []
    rx = [_pdo(device, p, strings) for p in device.rx_pdos if not device.esc_registers(p)] if pdo_categories else []

    # Eeprom/Category entries come first (as the vendor categories of the AKD/EL2262 dumps do); one of a
    # standard type (Elmo's boot devices give their own GENERAL and SYNCM) replaces the generated one.
    cats: list[Category] = [parse_category(c.cat_no, c.data + b"\x00" * (len(c.data) % 2))
                            for c in (eeprom.categories if eeprom else [])]
    given = {c.cat_type for c in cats}
    table = StringsCategory(strings.strings)
    if len(category_body(table)) != len(strings_content(table)):
        table.extra = b"\xff"  # the pad byte of an odd-length STRINGS body, as in the NI 9144 dumps
    generated: list[Category] = [table, general]
    if device.fmmus:
        usages = [FMMU_CODES.get(f.kind, 0) for f in device.fmmus]
        if len(usages) % 2 == 0 and usages[-1] == 0:
            usages.pop()  # a last unused FMMU is the same byte as the word padding; keep the model canonical
        generated.append(FmmuCategory(usages))
    if device.sync_managers:
        generated.append(SyncMCategory([
            SiiSyncManager(sm.start_address, sm.default_size or 0, sm.control_byte & 0xFF, 0,
                           _enable_byte(sm),
                           SM_TYPE_CODES.get(sm.kind, 0))
            for sm in device.sync_managers]))
    if any(f.sm is not None for f in device.fmmus):
        generated.append(RawCategory(CategoryType.FMMUX, b"".join(
            bytes([0xFA, 0xFF, 0xFF if f.sm is None else f.sm & 0xFF, (f.su or 0) & 0xFF]) for f in device.fmmus)))
    if tx:
        generated.append(PdoCategory(CategoryType.TXPDO, tx))
    if rx:
        generated.append(PdoCategory(CategoryType.RXPDO, rx))
    if dc_ops:
        generated.append(DcCategory(dc_ops))
    cats += [c for c in generated if c.cat_type not in given]

    if eeprom and eeprom.byte_size and eeprom.byte_size >= 128:
        h.size_word = eeprom.byte_size // 128 - 1
    return SiiImage(h, cats, True, b"", device.source)
