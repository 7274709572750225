"""Integrity checks of an SII image (``sii check``) and of an image against an ESI device.

Rule ids: ``sii.parse``, ``sii.blank``, ``sii.crc``, ``sii.length``, ``sii.size``, ``sii.version``,
``sii.end``, ``sii.category``, ``sii.strings``, ``sii.general``, ``sii.fmmu``, ``sii.sm``, ``sii.mailbox``,
``sii.pdo``, ``sii.vendor``; against an ESI: ``sii.esi.identity``, ``sii.esi.mailbox``, ``sii.esi.sm``,
``sii.esi.pdo`` (errors) and ``sii.esi.config``, ``sii.esi.size``, ``sii.esi.fmmu``, ``sii.esi.dc`` (warnings).
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

from ecattool.errors import InputError, Location
from ecattool.findings import Finding, Severity
from ecattool.sii.crc import preamble_crc
from ecattool.sii.image import load
from ecattool.sii.model import (
    FMMU_USAGE,
    HEADER_BYTES,
    SM_TYPES,
    CategoryType,
    DcCategory,
    GeneralCategory,
    PdoCategory,
    RawCategory,
    SiiImage,
    category_body,
    category_name,
    fix_crc,
)

if TYPE_CHECKING:
    from ecattool.esi.model import Device

E, W, I = Severity.ERROR, Severity.WARNING, Severity.INFO


def category_offsets(image: SiiImage) -> list[int]:
    """Byte offset of each category header in the serialized image."""
    out = []
    pos = HEADER_BYTES
    for c in image.categories:
        out.append(pos)
        pos += 4 + len(category_body(c))
    return out


def set_alias(image: SiiImage, alias: int) -> SiiImage:
    """Set the configured station alias (word 4) and update the checksum, as TwinCAT does."""
    if not 0 <= alias <= 0xFFFF:
        raise InputError(f"station alias {alias} is out of range 0..65535")
    image.header.station_alias = alias
    return fix_crc(image)


class _Report:
    def __init__(self, source: str) -> None:
        self.source = source
        self.findings: list[Finding] = []

    def add(self, rule: str, sev: Severity, msg: str, offset: int | None = None, **data: Any) -> None:
        if offset is not None:
            msg = f"{msg} (byte 0x{offset:04X}, word 0x{offset // 2:04X})"
            data["offset"] = offset
        self.findings.append(Finding(rule, sev, msg, Location(self.source or None), data))


def check_file(path: str | Path, data: bytes | None = None) -> tuple[SiiImage | None, list[Finding]]:
    """Load and check an image file. A file that does not parse gives one ``sii.parse`` error (located)."""
    try:
        image = load(path, data)
    except InputError as exc:
        return None, [Finding("sii.parse", E, exc.message, exc.location or Location(str(path)))]
    return image, check(image)


def check(image: SiiImage) -> list[Finding]:
    r = _Report(image.source)
    raw = image.to_bytes()
    h = image.header
    head = raw[:HEADER_BYTES]
    if head == b"\xff" * HEADER_BYTES or head == bytes(HEADER_BYTES):
        r.add("sii.blank", E, f"the fixed area is all 0x{head[0]:02X}: the EEPROM is blank, not an SII image", 0)
    crc = preamble_crc(raw)
    if raw[14] != crc:
        r.add("sii.crc", E, f"checksum 0x{raw[14]:02X} does not match the CRC-8 of bytes 0-13 (0x{crc:02X}); "
              "run 'ecattool sii fix-crc'", 14, stored=raw[14], computed=crc)
    if raw[15] != 0:
        r.add("sii.crc", W, f"checksum high byte is 0x{raw[15]:02X}, 0x00 expected", 15)
    if len(raw) % 2:
        r.add("sii.length", E, f"image length {len(raw)} bytes is odd; the EEPROM is written in words", len(raw) - 1)
    used = len(raw) - len(image.tail)
    if h.size_word == 0xFFFF or h.eeprom_bytes & (h.eeprom_bytes - 1):
        r.add("sii.size", W, f"size word 0x{h.size_word:04X} does not declare a power-of-two EEPROM size", 0x7C)
    if used > h.eeprom_bytes:
        r.add("sii.size", E, f"the image needs {used} bytes but the size word declares a "
              f"{h.eeprom_bytes}-byte EEPROM (0x{h.size_word:04X}); it does not fit", h.eeprom_bytes,
              used=used, declared=h.eeprom_bytes)
    elif len(raw) > h.eeprom_bytes:
        r.add("sii.size", W, f"the file is {len(raw)} bytes, longer than the declared {h.eeprom_bytes}-byte EEPROM",
              h.eeprom_bytes)
    if h.version != 1:
        r.add("sii.version", W, f"version word is {h.version}, 1 expected", 0x7E)
    if h.vendor_id == 0:
        r.add("sii.vendor", W, "vendor id is 0 (no registered vendor); was the ESI <Vendor><Id> read?", 0x10)
    if not image.end_marker:
        r.add("sii.end", W, "the category list runs to the end of the data without the 0xFFFF end marker",
              len(raw))
    _check_categories(image, r)
    _check_sms(image, r)
    return r.findings


def _check_categories(image: SiiImage, r: _Report) -> None:
    offsets = category_offsets(image)
    counts: dict[int, int] = {}
    nstr = len(image.strings)
    for c, off in zip(image.categories, offsets):
        counts[c.cat_type] = counts.get(c.cat_type, 0) + 1
        name = category_name(c.cat_type)
        if isinstance(c, RawCategory) and c.problem:
            r.add("sii.category", E, f"{name} category does not decode: {c.problem}", off)
        refs: list[tuple[str, int]] = []
        if isinstance(c, GeneralCategory):
            refs = [("group", c.group_idx), ("image", c.image_idx), ("order", c.order_idx), ("name", c.name_idx),
                    ("group name (byte 0x0E)", c.group_name_idx)]
        elif isinstance(c, PdoCategory):
            for p in c.pdos:
                refs.append((f"PDO 0x{p.index:04X} name", p.name_idx))
                refs += [(f"PDO 0x{p.index:04X} entry {j} name", e.name_idx) for j, e in enumerate(p.entries)]
        elif isinstance(c, DcCategory):
            for j, o in enumerate(c.opmodes):
                refs += [(f"DC opmode {j} name", o.name_idx), (f"DC opmode {j} description", o.desc_idx)]
        for what, idx in refs:
            if idx > nstr:
                r.add("sii.strings", E, f"{name}: {what} refers to string {idx}, but there are only {nstr}", off)
    for t in (CategoryType.STRINGS, CategoryType.GENERAL, CategoryType.FMMU, CategoryType.SYNCM):
        if counts.get(t, 0) > 1:
            r.add("sii.category", W, f"{counts[t]} {category_name(t)} categories; readers use the first")
    if CategoryType.GENERAL not in counts:
        r.add("sii.general", W, "no GENERAL category: masters cannot read CoE/FoE details or the device name")
    if CategoryType.STRINGS not in counts and nstr == 0 and CategoryType.GENERAL in counts:
        r.add("sii.strings", W, "no STRINGS category")
    for i, u in enumerate(image.fmmus):
        if u not in FMMU_USAGE:
            r.add("sii.fmmu", W, f"FMMU {i} has usage 0x{u:02X} (0 none, 1 outputs, 2 inputs, 3 SyncM status)")


def _check_sms(image: SiiImage, r: _Report) -> None:
    sms = image.sync_managers
    h = image.header
    spans = []
    for i, s in enumerate(sms):
        if s.type not in SM_TYPES:
            r.add("sii.sm", E, f"SM{i} has type {s.type} (0 unused, 1 MBoxOut, 2 MBoxIn, 3 outputs, 4 inputs)")
        if s.enable & 1 and s.length and s.type:
            spans.append((s.start, s.start + s.length, i))
        if s.type == 3 and s.enable & 1 and s.length and not s.control & 0x40:
            r.add("sii.sm", I, f"SM{i} (outputs) control byte 0x{s.control:02X} has no watchdog trigger (bit 6)")
    spans.sort()
    for (a0, a1, i), (b0, b1, j) in zip(spans, spans[1:]):
        if b0 < a1:
            r.add("sii.sm", E, f"SM{i} (0x{a0:04X}-0x{a1 - 1:04X}) and SM{j} (0x{b0:04X}-0x{b1 - 1:04X}) overlap")
    if h.mailbox_protocols:
        mbx = {s.type: s for s in sms if s.type in (1, 2)}
        if sms and (1 not in mbx or 2 not in mbx):
            r.add("sii.mailbox", W, f"mailbox protocols {'/'.join(h.protocols)} are declared but the SyncM category "
                  "has no MBoxOut/MBoxIn pair")
        for t, off, size, what in ((1, h.std_rx_offset, h.std_rx_size, "receive (MBoxOut)"),
                                   (2, h.std_tx_offset, h.std_tx_size, "send (MBoxIn)")):
            mbx_sm = mbx.get(t)
            if mbx_sm is not None and (mbx_sm.start, mbx_sm.length) != (off, size):
                r.add("sii.mailbox", W, f"standard {what} mailbox 0x{off:04X}/{size} in the header differs from "
                      f"its sync manager 0x{mbx_sm.start:04X}/{mbx_sm.length}")
    for cat_type, want in ((CategoryType.TXPDO, 4), (CategoryType.RXPDO, 3)):
        for p in image.pdos(cat_type):
            if p.sm == 0xFF:
                continue
            if p.sm >= len(sms):
                if sms:
                    r.add("sii.pdo", E, f"PDO 0x{p.index:04X} is assigned to SM{p.sm}, which the SyncM category "
                          f"does not define ({len(sms)} sync managers)")
            elif sms[p.sm].type not in (want, 0):
                r.add("sii.pdo", E, f"{category_name(cat_type)} 0x{p.index:04X} is assigned to SM{p.sm} of type "
                      f"'{sms[p.sm].kind}', '{SM_TYPES[want]}' expected")


_AGAINST: list[tuple[str, str, Severity, str]] = [
    # (regex on the flattened field name, rule, severity, what)
    (r"header\.(vendor_id|product_code|revision)$", "sii.esi.identity", E, "identity"),
    (r"header\.(std_|bootstrap_|mailbox_protocols)", "sii.esi.mailbox", E, "mailbox"),
    (r"general\.(coe_details|foe_details|eoe_details)$", "sii.esi.mailbox", W, "mailbox details"),
    (r"header\.(pdi_control|pdi_config|sync_impulse_len|pdi_config2|reserved_05|reserved_06)$", "sii.esi.config", W,
     "ConfigData"),
    (r"header\.size_word$", "sii.esi.size", W, "EEPROM size"),
    (r"sm\[\d+\]\.(start|length|control|enable|type)$", "sii.esi.sm", E, "sync manager"),
    (r"fmmu\[\d+\]$", "sii.esi.fmmu", W, "FMMU"),
    (r"(tx|rx)pdo\[[^]]+\](\.sm|\.entries|\.entry\[\d+\]\.(index|subindex|bit_len))?$", "sii.esi.pdo", E, "PDO"),
    (r"dc\[\d+\]\.(assign_activate|cycle_time0|shift_time0)$", "sii.esi.dc", W, "DC"),
]


def built_image_problem(device: Device, image: SiiImage) -> str | None:
    """Why ``image``, built from ``device`` (``sii build``), fails :func:`check`, or None when it passes: the image is
    what the ESI says, and where the ESI's own Eeprom/Category elements replace generated ones (as Elmo's boot
    devices give a 9-byte SyncM) that is named as the likely cause."""
    errors = [f for f in check(image) if f.severity is Severity.ERROR]
    if not errors:
        return None
    given = sorted({c.cat_no for c in device.eeprom.categories}) if device.eeprom else []
    why = f"; the ESI's Eeprom/Category {', '.join(map(str, given))} replaces what ecattool generates" if given else ""
    return f"the image fails `sii check` with {len(errors)} error(s), first: {errors[0].message}{why}"


def check_against(device: "Device", image: SiiImage) -> list[Finding]:
    """Where ``image`` and the ESI ``device`` disagree: identity, mailbox, ConfigData, SMs, FMMUs, PDOs, DC.

    PDOs are compared only when the image has PDO categories, DC modes only when it has a DC category
    (both are optional in an SII)."""
    import re

    from ecattool.sii.builder import assemble
    from ecattool.sii.compare import flatten

    expected = assemble(device)
    got, want = flatten(image), flatten(expected)
    has_pdos = bool(image.tx_pdos or image.rx_pdos)
    has_dc = bool(image.dc_opmodes)
    eeprom = device.eeprom
    skip = set()
    if not (eeprom and eeprom.byte_size):
        skip.add("sii.esi.size")  # the ESI does not say
    if not (eeprom and eeprom.config_data):
        skip.add("sii.esi.config")
    r = _Report(image.source)
    dev = f"{device.type_name} ({device.identity})"
    for key in list(want) + [k for k in got if k not in want]:
        a, b = got.get(key), want.get(key)
        if a == b or (key.startswith(("txpdo", "rxpdo")) and not has_pdos) or (key.startswith("dc") and not has_dc):
            continue
        if re.match(r"sm\[\d+\]\.enable$", key) and isinstance(a, int) and isinstance(b, int) and a ^ b == 0x08:
            # only the OP-only bit (ESI Sm@OpOnly); generators such as siitool do not write it
            r.add("sii.esi.sm", W, f"sync manager: {key} is {_fmt(a)} in the image but {_fmt(b)} in the ESI device "
                  f"{dev} (only bit 3, OP only, differs)", field=key)
            continue
        for pattern, rule, sev, what in _AGAINST:
            if re.match(pattern, key):
                if rule in skip:
                    break
                r.add(rule, sev, f"{what}: {key} is {_fmt(a)} in the image but {_fmt(b)} in the ESI device {dev}",
                      field=key)
                break
    if not has_pdos and (device.tx_pdos or device.rx_pdos):
        r.add("sii.esi.pdo", I, "the image has no PDO categories; masters read the PDOs over CoE or from the ESI")
    return r.findings


def _fmt(v: Any) -> str:
    if v is None:
        return "absent"
    if isinstance(v, int) and not isinstance(v, bool):
        return f"0x{v:X}"
    return repr(v)
