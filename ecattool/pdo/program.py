"""The SDO sequence that installs a mapping, as a startup list.

Standard order (ETG.1000.6 / CiA-301, Technosoft §2.4, field-notes §4.7), in three phases over both
directions:

1. ``1C12:00 = 0`` / ``1C13:00 = 0`` (UNSIGNED8): the assignments are disabled;
2. per rewritten mapping object: ``16xx:00 = 0`` (UNSIGNED8), ``16xx:k = index<<16|sub<<8|bits``
   (UNSIGNED32), ``16xx:00 = n`` (UNSIGNED8);
3. ``1C12:k = 0x16xx`` (UNSIGNED16) for k = 1..n, then ``1C12:00 = n`` (UNSIGNED8); the same for 1C13.

With complete access, phase 2 and 3 write each object in one transfer at sub-index 0 with the data
``n, 0x00 (pad), entry…`` (sub-index 0 padded to 16 bits). ``order="count-first"`` reproduces the Control
Techniques quick start literally (count first, then entries, no disabling writes).

Fixed PDOs are assigned but never rewritten; PDOs whose entries were not given keep their contents. A device
without a CoE mailbox gets no SDO at all: its process image is fixed.
"""

from __future__ import annotations

from collections.abc import Iterable

from ecattool.errors import InputError, Location
from ecattool.esi.model import Device, Direction
from ecattool.pdo.model import MappedPdo, Mapping, default_mapping, entry_keys, without_virtual
from ecattool.profiles import rules_for
from ecattool.profiles.rules import FamilyRules
from ecattool.startup.model import StartupCommand, StartupList

ORDERS = ("standard", "count-first")


def _le(value: int, size: int, what: str, location: Location | None = None) -> bytes:
    """``value`` as ``size`` little-endian bytes; a value that does not fit (a mapping with 300 entries, an entry
    of 0x1FFFF:00 forced through ``map sdo --force``) is a located error, not an OverflowError."""
    try:
        return value.to_bytes(size, "little")
    except OverflowError:
        raise InputError(f"{what}: {value} does not fit {size} byte(s) (0..{(1 << 8 * size) - 1})"
                         if value >= 0 else f"{what}: {value} is negative", location) from None


def _u8(n: int, location: Location | None = None) -> bytes:
    return _le(n, 1, "count", location)


def _cmd(transition: str, index: int, sub: int, value: int, size: int, comment: str,
         source: Location | None, complete_access: bool = False, data: bytes | None = None) -> StartupCommand:
    type_name = {1: "USINT", 2: "UINT", 4: "UDINT"}[size] if data is None else "OCTET_STRING"
    return StartupCommand(
        transition=transition, index=index, subindex=sub,
        data=data if data is not None else _le(value, size, comment, source),
        comment=comment, complete_access=complete_access, type_name=type_name, value=value, source=source,
    )


def resolve_rules(device: Device, rules: FamilyRules | None) -> FamilyRules:
    """The family rules to use: the given ones, else the device family's (``ecattool.profiles.rules_for``)."""
    if rules is not None:
        return rules

    return rules_for(device)


def rewritten(device: Device, pdo: MappedPdo, rules: FamilyRules | None = None,
              power_on: Mapping | None = None) -> bool:
    """Whether :func:`program` writes the mapping object of ``pdo`` (given with entries): where the family lets
    mapping objects be written and the PDO is not Fixed; else only where the entries differ from the PDO's own
    (the drive then refuses them, as ``check`` says)."""
    rules = resolve_rules(device, rules)
    dev_pdo = device.pdo(pdo.index)
    if rules.mapping_writable and not (dev_pdo is not None and dev_pdo.fixed):
        return True
    if power_on is None:
        power_on = default_mapping(device)
    own = dev_pdo.entries if dev_pdo is not None else next(
        (p.entries for p in (*power_on.rx, *power_on.tx) if p.index == pdo.index), [])
    return entry_keys(pdo.entries) != entry_keys(own)


def program(
    device: Device,
    mapping: Mapping,
    complete_access: bool = False,
    transition: str = "PS",
    baseline: Mapping | None = None,
    order: str = "standard",
    rules: FamilyRules | None = None,
    directions: Iterable[Direction] | None = None,
) -> StartupList:
    """The startup list that installs ``mapping`` on ``device``.

    ``directions`` defaults to the directions the mapping was given for (both when none is marked).
    ``baseline`` (the mapping the drive holds now, e.g. :func:`default_mapping`) leaves out mapping objects
    whose entries already match and assignment sub-indices that already hold the right PDO; the
    assignment is still disabled and re-enabled. ``complete_access`` is used only when the device
    advertises it (``CoE@CompleteAccess``).
    """
    if order not in ORDERS:
        raise InputError(f"unknown programming order {order!r} (use {' or '.join(ORDERS)})")
    rules = resolve_rules(device, rules)
    mapping = without_virtual(device, mapping)[0]  # ESC registers: no SDO assigns or maps them
    dirs = [d for d in Direction if d in set(directions if directions is not None else (mapping.given or Direction))]
    coe = device.mailbox.coe if device.mailbox is not None else None
    ca = bool(complete_access and coe is not None and coe.complete_access)
    count_first = order == "count-first"
    out = StartupList(name=device.name or device.type_name, vendor_id=device.vendor_id,
                      product_code=device.product_code, revision=device.revision)

    if not device.has_coe:
        return out  # no mailbox: a fixed process image, nothing to write (check says where that differs: PDO022/023)
    power_on = default_mapping(device)

    def assignable(d: Direction) -> bool:
        if rules.assign_writable and (not device.dictionary or d.assign_index in device.dictionary):
            return True
        # not changeable: write only when asked for something else (the drive then refuses it, as check says)
        return [p.index for p in mapping.pdos(d)] != [p.index for p in power_on.pdos(d)]

    def rewritable(pdo: MappedPdo) -> bool:
        return rewritten(device, pdo, rules, power_on)

    # phase 1: disable the assignments
    if not count_first:
        for d in dirs:
            if assignable(d):
                out.commands.append(_cmd(transition, d.assign_index, 0, 0, 1,
                                         f"clear sm pdos (0x{d.assign_index:04X})",
                                         Location(mapping.source) if mapping.source else None))
    # phase 2: rewrite the mapping objects (never a Fixed PDO or an unwritable one with its own contents)
    done: set[int] = set()
    base_pdos = {p.index: p for p in (*(baseline.rx if baseline else ()), *(baseline.tx if baseline else ()))}
    for d in dirs:
        for pdo in mapping.pdos(d):
            if not pdo.explicit or pdo.index in done or not rewritable(pdo):
                continue
            base = base_pdos.get(pdo.index)
            if base is not None and entry_keys(base.entries) == entry_keys(pdo.entries):
                continue
            done.add(pdo.index)
            out.commands.extend(_mapping_commands(pdo, transition, ca, count_first))
    # phase 3: the assignments
    for d in dirs:
        if not assignable(d):
            continue
        pdos = mapping.pdos(d)
        n = len(pdos)
        idx = d.assign_index
        src = pdos[0].location if pdos else None
        if ca:
            data = _u8(n, src) + b"\x00" + b"".join(_le(p.index, 2, "PDO index", p.location) for p in pdos)
            out.commands.append(_cmd(transition, idx, 0, n, 1, f"download pdo 0x{idx:04X} (complete access)", src,
                                     True, data))
            continue
        old = [p.index for p in baseline.pdos(d)] if baseline is not None else []
        entries = [
            _cmd(transition, idx, k, p.index, 2, f"download pdo 0x{idx:04X}:{k:02X} index", p.location)
            for k, p in enumerate(pdos, start=1)
            if not (k <= len(old) and old[k - 1] == p.index)
        ]
        count = _cmd(transition, idx, 0, n, 1, f"download pdo 0x{idx:04X} count", src)
        out.commands.extend([count, *entries] if count_first else [*entries, count])
    return out


def _mapping_commands(pdo: MappedPdo, transition: str, ca: bool, count_first: bool) -> list[StartupCommand]:
    n = len(pdo.entries)
    idx = pdo.index
    if ca:
        data = _u8(n, pdo.location) + b"\x00" + b"".join(
            _le(e.mapping_value, 4, "mapping entry", e.location or pdo.location) for e in pdo.entries)
        return [_cmd(transition, idx, 0, n, 1, f"download pdo 0x{idx:04X} entries (complete access)", pdo.location,
                     True, data)]
    entries = [
        _cmd(transition, idx, k, e.mapping_value, 4, f"download pdo 0x{idx:04X}:{k:02X} entry", e.location or pdo.location)
        for k, e in enumerate(pdo.entries, start=1)
    ]
    count = _cmd(transition, idx, 0, n, 1, f"download pdo 0x{idx:04X} entry count", pdo.location)
    if count_first:
        return [count, *entries]
    clear = _cmd(transition, idx, 0, 0, 1, f"clear pdo 0x{idx:04X} entries", pdo.location)
    return [clear, *entries, count]
