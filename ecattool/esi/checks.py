"""Structural checks of an ESI model that need no schema (rule ids ``esi-…``).

* ``esi-pdo-duplicate`` — two PDOs of one device share an index;
* ``esi-pdo-object-missing`` — a PDO entry names an object/sub-index the device's dictionary lacks;
* ``esi-pdo-bitlen`` — an entry's BitLen is larger than the dictionary entry's bit size;
* ``esi-pdo-partial`` (info) — an entry maps the low bits of a larger object (a vendor's "compact" PDO);
* ``esi-pdo-standard-object`` (info) — an entry maps a standard object the dictionary leaves out but every
  device has by ETG.1000.6 (:func:`standard_entry_bits`);
* ``esi-pdo-sm-missing`` / ``esi-pdo-sm-direction`` — a PDO's default Sm does not exist or carries the
  other direction;
* ``esi-sm-size`` — the default process image of a sync manager is larger than its MaxSize;
* ``esi-exclude-missing`` — an Exclude names a PDO the device does not define;
* ``esi-pdo-default-differs`` — a mapping object's DefaultData in the dictionary lays out other entries than
  its ``<RxPdo>``/``<TxPdo>`` element (beyond trailing padding): the ESI contradicts itself; the slave powers on
  with the dictionary's (:mod:`ecattool.esi.power_on`). An error where the image differs, a warning where only
  the objects named differ;
* ``esi-product-zero`` — the device's product code is 0 (an EDS without ProductNumber and 1018h:02 default,
  an ESI ProductCode of 0): a master configuration made from it expects product 0, which no real drive reports.
"""

from __future__ import annotations

from ecattool.esi.model import Device, Direction, EsiFile, Pdo, with_article
from ecattool.findings import Finding, Severity


#: rule id -> what it means (lint's SARIF rule descriptions)
RULES: dict[str, str] = {
    "esi-pdo-duplicate": "two PDOs of one device share an index",
    "esi-pdo-object-missing": "a PDO entry names an object or sub-index the device's dictionary lacks",
    "esi-pdo-bitlen": "a PDO entry's BitLen is larger than the dictionary entry's bit size",
    "esi-pdo-partial": "a PDO entry maps the low bits of a larger object (a compact PDO): the vendor's definition",
    "esi-pdo-standard-object": "a PDO entry maps a standard object the ESI's dictionary leaves out; the device has it",
    "esi-pdo-sm-missing": "a PDO's default Sm does not exist",
    "esi-pdo-sm-direction": "a PDO's default Sm carries the other direction",
    "esi-sm-size": "the default process image of a sync manager is larger than its MaxSize",
    "esi-exclude-missing": "an Exclude names a PDO the device does not define",
    "esi-product-zero": "the device's product code is 0: exported master configurations would expect product 0",
    "esi-pdo-default-differs": "a mapping object's DefaultData contradicts its RxPdo/TxPdo element: the slave powers "
                               "on with the dictionary's",
}


#: communication area (ETG.1000.6 / CiA 301): the objects of 1000h-1FFFh are the standard's, whatever the ESI's
#: dictionary lists of them
COMMUNICATION_AREA = range(0x1000, 0x2000)


def standard_entry_bits(index: int, subindex: int, has_object: bool) -> int | None:
    """The bit size of ``index:subindex`` where a device has it by the standard although its ESI's dictionary
    leaves it out, else None:

    * 1800h-1BFFh sub 7 (TxPDO State) and sub 9 (TxPDO Toggle), BOOLEAN: ETG.1000.6 TxPDO parameter objects,
      which Beckhoff terminals map into their TxPDOs and leave out of the ESI's dictionary;
    * 1C32h/1C33h sub 20h (Sync Error), BOOLEAN: ETG.1020 sync manager parameter;
    * 10F4h (External Synchronization Status, ETG.1000.6) sub 1-12h, 0 (any size): the EL6688/EL6692 map its
      sync mode, update toggles and time stamps, and their ESIs' dictionaries leave the object out;
    * 0 (any size) for another sub-index of a communication-area object the dictionary has (``has_object``):
      the ESI lists a subset of a standard object's sub-indices (an EL6688's 10F4h:02)."""
    if 0x1800 <= index <= 0x1BFF and subindex in (7, 9):
        return 1
    if index in (0x1C32, 0x1C33) and subindex == 0x20:
        return 1
    if index == 0x10F4 and 1 <= subindex <= 0x12:
        return 0
    if has_object and index in COMMUNICATION_AREA:
        return 0
    return None


def _f(rule: str, sev: Severity, msg: str, loc: object, **data: object) -> Finding:
    return Finding(rule, sev, msg, loc, dict(data))  # type: ignore[arg-type]


def default_image(dev: Device, sm_number: int) -> list[Pdo]:
    """PDOs assigned to ``sm_number`` by default (their @Sm), skipping those excluded by one taken before."""
    taken: list[Pdo] = []
    excluded: set[int] = set()
    for pdo in (*dev.rx_pdos, *dev.tx_pdos):
        if pdo.sm != sm_number or pdo.index in excluded or dev.esc_registers(pdo):
            continue
        taken.append(pdo)
        excluded.update(pdo.excludes)
    return taken


def check_device(dev: Device) -> list[Finding]:
    out: list[Finding] = []
    name = dev.type_name or f"0x{dev.product_code:08X}"
    pdos = [*dev.rx_pdos, *dev.tx_pdos]
    seen: dict[int, Pdo] = {}
    for pdo in pdos:
        if pdo.index in seen and not (pdo.virtual or seen[pdo.index].virtual):
            out.append(_f("esi-pdo-duplicate", Severity.ERROR,
                          f"{name}: PDO 0x{pdo.index:04X} is defined twice", pdo.location, pdo=pdo.index))
        seen.setdefault(pdo.index, pdo)
    if dev.product_code == 0:
        fmt = dev.extra.get("format")
        where = (f"the {fmt} has no ProductNumber in [DeviceInfo] and no 1018h:02 default" if fmt in ("EDS", "DCF")
                 else "its Type ProductCode is 0")
        out.append(_f("esi-product-zero", Severity.WARNING,
                      f"{name}: product code 0 ({where}); every master configuration exported from it expects "
                      "product 0 and a master that checks the identity refuses the real drive: use the vendor's "
                      "ESI, or set 'identity: {product: false}' on the drive in the project", dev.location))
    od = dev.dictionary
    check_od = len(od) > 0
    for pdo in pdos:
        if dev.esc_registers(pdo):
            continue  # ESC registers (1D09h:98h = register 0998h) through an FMMU: no object, no sync manager
        if check_od and not pdo.depend_on_slot:
            for e in pdo.entries:
                if e.is_gap or e.depend_on_slot or 1 <= e.index <= 7:
                    continue  # a gap, or a dummy: data-type indices 1h-7h (BOOLEAN..UNSIGNED32) pad, name no object
                entry = od.entry(e.index, e.subindex)
                where = f"{name}: PDO 0x{pdo.index:04X} maps 0x{e.index:04X}:{e.subindex:02X}"
                if entry is None:
                    what = "object" if e.index not in od else "sub-index"
                    bits = standard_entry_bits(e.index, e.subindex, e.index in od)
                    if bits is not None and bits in (0, e.bit_len):
                        out.append(_f("esi-pdo-standard-object", Severity.INFO,
                                      f"{where} ({e.name or '?'}), a standard {what} the dictionary leaves out: the "
                                      "device has it by ETG.1000.6 (ecattool takes the entry as the PDO list gives it)",
                                      e.location, pdo=pdo.index))
                        continue
                    out.append(_f("esi-pdo-object-missing", Severity.ERROR,
                                  f"{where} ({e.name or '?'}), but the dictionary has no such {what}", e.location,
                                  pdo=pdo.index))
                elif entry.bit_size and entry.bit_size < e.bit_len:
                    out.append(_f("esi-pdo-bitlen", Severity.ERROR,
                                  f"{where} with BitLen {e.bit_len}, but the dictionary entry has {entry.bit_size} bits",
                                  e.location, pdo=pdo.index))
                elif entry.bit_size and entry.bit_size != e.bit_len:
                    out.append(_f("esi-pdo-partial", Severity.INFO,
                                  f"{where} with BitLen {e.bit_len}: the low {e.bit_len} bits of the {entry.bit_size}-bit "
                                  "object (a compact PDO, the vendor's definition)", e.location, pdo=pdo.index))
        if pdo.sm is not None:
            sm = dev.sm(pdo.sm)
            tag = "RxPdo" if pdo.direction is Direction.RX else "TxPdo"
            if sm is None:
                out.append(_f("esi-pdo-sm-missing", Severity.ERROR,
                              f"{name}: {tag} 0x{pdo.index:04X} is assigned to Sm {pdo.sm}, which the device does not define",
                              pdo.location, pdo=pdo.index))
            elif sm.direction is not None and sm.direction is not pdo.direction:
                out.append(_f("esi-pdo-sm-direction", Severity.ERROR,
                              f"{name}: {tag} 0x{pdo.index:04X} is assigned to Sm {pdo.sm} ({sm.kind}); "
                              f"{with_article(tag)} belongs in {with_article(pdo.direction.sm_kind)} sync manager",
                              pdo.location, pdo=pdo.index))
        for ex in pdo.excludes:
            if ex not in seen:
                out.append(_f("esi-exclude-missing", Severity.WARNING,
                              f"{name}: PDO 0x{pdo.index:04X} excludes 0x{ex:04X}, which the device does not define",
                              pdo.location, pdo=pdo.index))
    out.extend(_contradictions(dev, name))
    for sm in dev.sync_managers:
        if sm.max_size is None or sm.direction is None or sm.virtual:
            continue
        image = default_image(dev, sm.number)
        size = (sum(p.bit_size for p in image) + 7) // 8
        if size > sm.max_size:
            out.append(_f("esi-sm-size", Severity.ERROR,
                          f"{name}: default process image of Sm {sm.number} is {size} bytes, more than its MaxSize {sm.max_size}",
                          sm.location, sm=sm.number, size=size))
    return out


def _values(values: list[int]) -> str:
    return ", ".join(f"0x{v >> 16:04X}:{(v >> 8) & 0xFF:02X}/{v & 0xFF}" for v in values) or "nothing"


def _contradictions(dev: Device, name: str) -> list[Finding]:
    """``esi-pdo-default-differs``: at the dictionary object's line, naming the PDO element's."""
    from ecattool.esi.power_on import contradictions

    out = []
    for c in contradictions(dev):
        tag = "RxPdo" if c.pdo.direction is Direction.RX else "TxPdo"
        line = c.pdo.location.line if c.pdo.location is not None else None
        bits = sum(v & 0xFF for v in c.held), sum(v & 0xFF for v in c.listed)
        what = ("the same bits, other objects" if c.same_image
                else f"{bits[0]} bits against {bits[1]}: masters that read the slave lay out another image")
        out.append(_f("esi-pdo-default-differs", Severity.WARNING if c.same_image else Severity.ERROR,
                      f"{name}: the dictionary's mapping object 0x{c.pdo.index:04X} holds {_values(c.held)} by "
                      f"default, its {tag} element{f' (line {line})' if line else ''} {_values(c.listed)} ({what}); "
                      "the slave powers on with the dictionary's (ecattool's map layout, SII and simulator take it)",
                      c.location or c.pdo.location, pdo=c.pdo.index))
    return out


def check_structure(esi: EsiFile) -> list[Finding]:
    """Schema-free structural checks of every device in ``esi`` (see the module docstring for the rules)."""
    out: list[Finding] = []
    for dev in esi.devices:
        out.extend(check_device(dev))
    return out
