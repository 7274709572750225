"""Any CoE device from its ESI: family rules derived from the ESI, and a dictionary completed from its PDOs.

ESI files often leave the communication objects out of their ``Dictionary`` (or have no dictionary at all):
:func:`complete_generic` synthesises 1000h, 1018h, 1C00h, the mapping objects 16xxh/1Axxh and the
assignment objects 1C12h/1C13h from the device's identity, sync managers and PDO list, so that the
simulator can serve any ESI drive the same way as a built-in family.
"""

from __future__ import annotations

import copy

from ecattool.errors import Location
from ecattool.esi.model import Device, Direction, InitCmd, Module, Pdo, Slot
from ecattool.od.model import RO, Access, Entry, ObjectCode, ObjectDictionary, OdObject
from ecattool.od.types import STRING, UDINT, UINT, USINT, DataType, for_size, lookup
from ecattool.profiles.rules import FamilyRules

#: SM kinds → 1C00h communication type values (ETG.1000.6: 1 mailbox out, 2 mailbox in, 3 outputs, 4 inputs)
SM_TYPE = {"MBoxOut": 1, "MBoxIn": 2, "Outputs": 3, "Inputs": 4}

_PREOP_RW = Access.parse("rw", None, "PreOP")


def _u(sub: int, name: str, dt: DataType, value: int, access: Access = RO, where: str = "") -> Entry:
    assert dt.bits is not None, "only fixed-size types are synthesised"
    return Entry(sub, name, dt, dt.bits, access=access, default=dt.encode(value), location=Location(where or None))


def _all_pdos(device: Device, direction: Direction) -> list[Pdo]:
    seen: dict[int, Pdo] = {}
    for p in device.pdos(direction):
        seen.setdefault(p.index, p)
    return [seen[k] for k in sorted(seen)]


def _shift(index: int, offset: int) -> int:
    return index + offset if index >= 0x2000 else index


def _default_modules(device: Device) -> list[tuple[int, Slot, Module]]:
    """(slot number k, slot, its default module) of each slot that has a default module the device knows."""
    by_ident = {m.ident: m for m in device.modules if m.ident is not None}
    out = []
    for k, slot in enumerate(device.slots):
        module = by_ident.get(slot.default_module) if slot.default_module is not None else None
        if module is not None:
            out.append((k, slot, module))
    return out


def expand_default_modules(device: Device) -> tuple[list[Pdo], list[OdObject]]:
    """PDOs and objects of each slot's default module, with the slot increments applied.

    Slot k (0-based) moves a ``DependOnSlot`` PDO by k × SlotPdoIncrement and the objects it maps (and the
    module's dictionary objects) by k × SlotIndexIncrement; the model keeps DependOnSlot only on the PDO,
    so its entries are taken to depend on the slot too (decision "Profiles: slot expansion").
    """
    pdos: list[Pdo] = []
    objects: list[OdObject] = []
    for k, slot, module in _default_modules(device):
        obj_off = k * (slot.slot_index_increment or 0)
        for p in (*module.rx_pdos, *module.tx_pdos):
            q = copy.deepcopy(p)
            if p.depend_on_slot:
                q.index = p.index + k * (slot.slot_pdo_increment or 0)
                for e in q.entries:
                    e.index = _shift(e.index, obj_off) if not e.is_gap else 0
            pdos.append(q)
        for o in module.dictionary:
            c = copy.deepcopy(o)
            c.index = _shift(o.index, obj_off)
            objects.append(c)
    return pdos, objects


def _mapping_object(pdo: Pdo, writable: bool, where: str) -> OdObject:
    acc = _PREOP_RW if writable else RO
    obj = OdObject(pdo.index, pdo.name or f"{'Rx' if pdo.direction is Direction.RX else 'Tx'}PDO 0x{pdo.index:04X}",
                   ObjectCode.RECORD, location=Location(where))
    n = len(pdo.entries)
    obj.entries[0] = _u(0, "Number of mapped objects", USINT, n, acc, where)
    obj.entries[0].maximum = max(n, 1)
    for i, e in enumerate(pdo.entries, start=1):
        obj.entries[i] = _u(i, f"Mapping entry {i}", UDINT, e.mapping_value, acc, where)
    return obj


def _assign_object(device: Device, direction: Direction, pdos: list[Pdo], writable: bool, where: str) -> OdObject:
    sm = device.process_sm(direction)
    sm_no = sm.number if sm is not None else (2 if direction is Direction.RX else 3)
    assigned = [p.index for p in pdos if p.sm == sm_no or (p.sm is None and p.mandatory)]
    acc = _PREOP_RW if writable else RO
    label = "RxPDO" if direction is Direction.RX else "TxPDO"
    obj = OdObject(direction.assign_index, f"{label} assign", ObjectCode.ARRAY, location=Location(where))
    slots = max(len(pdos), 1)
    obj.entries[0] = _u(0, "Number of assigned PDOs", USINT, len(assigned), acc, where)
    obj.entries[0].maximum = slots
    for s in range(1, slots + 1):
        value = assigned[s - 1] if s <= len(assigned) else 0
        obj.entries[s] = _u(s, f"Assigned {label} {s}", UINT, value, acc, where)
    return obj


def plug_default_modules(device: Device) -> Device:
    """A copy of ``device`` with each slot's default module plugged in, as an ESI-configured master starts a
    modular device: the module PDOs and dictionary objects (:func:`expand_default_modules`) the device does
    not have itself are added; what the device's own PDO list and dictionary say wins. The one rule for "the
    device as it runs" that lint, the simulator and the exports share (docs/decisions.md, "Profiles: slot
    expansion")."""
    out = copy.deepcopy(device)
    if not out.slots:
        return out
    od = ObjectDictionary({o.index: o for o in out.dictionary})
    pdos, objects = expand_default_modules(out)
    known = {p.index for p in (*out.rx_pdos, *out.tx_pdos)}
    for p in pdos:
        if p.index not in known:
            out.pdos(p.direction).append(p)
            known.add(p.index)
    for o in objects:
        if o.index not in od:
            od.add(o)
    out.dictionary = od
    return out


def complete_generic(device: Device) -> Device:
    """A copy of ``device`` whose dictionary has 1000h, 1018h, 1C00h, 16xxh/1Axxh and 1C12h/1C13h.

    Objects the ESI already defines are kept as they are; only missing ones are synthesised (from the
    identity, the sync managers and the PDO list, with each PDO's default SM deciding its assignment).
    Mapping objects of Fixed PDOs, and the assignment when the ESI does not declare PdoAssign, are read-only.
    """
    out = plug_default_modules(device)
    od = ObjectDictionary({o.index: o for o in out.dictionary})
    where = f"synthesised from {device.source or device.type_name}"
    coe = out.mailbox.coe if out.mailbox is not None else None
    if 0x1000 not in od:
        value = (out.profile_no or 0) & 0xFFFF
        od.add(OdObject(0x1000, "Device type", ObjectCode.VAR, {0: _u(0, "Device type", UDINT, value, RO, where)},
                        location=Location(where)))
    if 0x1008 not in od and (out.name or out.type_name):
        text = (out.name or out.type_name).encode("latin-1", "replace")
        od.add(OdObject(0x1008, "Device name", ObjectCode.VAR,
                        {0: Entry(0, "Device name", STRING, 8 * len(text), access=Access.parse("const"), default=text,
                                  location=Location(where))}, location=Location(where)))
    ident = out.identity
    obj = OdObject(0x1018, "Identity", ObjectCode.RECORD, location=Location(where))
    for sub, name, value in ((0, "Number of entries", 4), (1, "Vendor ID", ident.vendor_id),
                             (2, "Product code", ident.product_code), (3, "Revision", ident.revision),
                             (4, "Serial number", ident.serial)):
        obj.entries[sub] = _u(sub, name, USINT if sub == 0 else UDINT, value, RO, where)
    existing = od.get(0x1018)
    if existing is None:
        od.add(obj)
    else:
        _fill_entries(existing, obj)
        # The device's identity (Type@ProductCode/RevisionNo, Vendor/Id) is what the drive reports; ESI 1018h
        # defaults are often stale (Ingenia, Inovance and the ETG.2001 example disagree with their Type).
        for sub in (1, 2, 3):
            e = existing.entry(sub)
            if e is not None and e.datatype is not None and e.bit_size == 32:
                e.default = obj.entries[sub].default
    if out.sync_managers:
        sms = sorted(out.sync_managers, key=lambda s: s.number)
        obj = OdObject(0x1C00, "Sync manager type", ObjectCode.ARRAY, location=Location(where))
        obj.entries[0] = _u(0, "Number of sync managers", USINT, len(sms), RO, where)
        for sm in sms:
            obj.entries[sm.number + 1] = _u(sm.number + 1, f"SM{sm.number} type", USINT, SM_TYPE.get(sm.kind, 0), RO, where)
        existing = od.get(0x1C00)
        if existing is None:
            od.add(obj)
        else:
            # an ESI 1C00h without DefaultData (Copley XE2, EM7004) would read 0 for every SM, and a master that
            # finds the process data SMs through it (KickCAT's create_mapping) would map nothing
            _fill_defaults(existing, obj)
    config = bool(coe and coe.pdo_config)
    assign = bool(coe and coe.pdo_assign)
    for direction in (Direction.RX, Direction.TX):
        pdos = _all_pdos(out, direction)
        for p in pdos:
            mapping = od.get(p.index)
            if mapping is None:
                od.add(_mapping_object(p, config and not p.fixed, where))
            else:
                _fill_defaults(mapping, _mapping_object(p, False, where))
        if pdos:
            assignment = od.get(direction.assign_index)
            if assignment is None:
                od.add(_assign_object(out, direction, pdos, assign, where))
            else:
                _fill_defaults(assignment, _assign_object(out, direction, pdos, False, where))
    _add_mapped_objects(od, out, where)
    out.dictionary = od
    return out


def _add_mapped_objects(od: ObjectDictionary, device: Device, where: str) -> None:
    """Objects that a PDO maps but the ESI's dictionary lacks, from the PDO entry (name, type, bit length)."""
    for p in (*device.rx_pdos, *device.tx_pdos):
        for e in p.entries:
            if e.is_gap or od.entry(e.index, e.subindex) is not None or e.index < 0x1000:
                continue
            dt = lookup(e.data_type) if e.data_type else None
            if dt is None or (dt.bits is not None and dt.bits != e.bit_len and not dt.is_bit_type):
                dt = for_size(e.bit_len) if e.bit_len in (8, 16, 24, 32, 40, 48, 56, 64) else lookup(f"BIT{e.bit_len}")
            acc = Access.parse("rw") if p.direction is Direction.RX else RO
            entry = Entry(e.subindex, e.name or f"Object 0x{e.index:04X}:{e.subindex:02X}", dt, e.bit_len, access=acc,
                          pdo_mapping="R" if p.direction is Direction.RX else "T", location=Location(where))
            if dt is not None and dt.bits is not None:
                entry.default = bytes((e.bit_len + 7) // 8)
            obj = od.get(e.index)
            if obj is None:
                code = ObjectCode.VAR if e.subindex == 0 else ObjectCode.RECORD
                obj = OdObject(e.index, e.name or f"Object 0x{e.index:04X}", code, location=Location(where))
                od.add(obj)
            obj.entries[e.subindex] = entry
            if obj.object_code is not ObjectCode.VAR and 0 not in obj.entries:
                obj.entries[0] = _u(0, "Number of entries", USINT, 0, RO, where)
            if 0 in obj.entries and obj.object_code is not ObjectCode.VAR:
                obj.entries[0].default = bytes([max(obj.entries)])


def _fill_defaults(existing: OdObject, synthesised: OdObject) -> None:
    """Give an ESI object without default values (e.g. 1C12h with no ``DefaultData``) the PDO list's values."""
    if existing.entry(0) is None or existing.entries[0].default is not None:
        return
    _fill_entries(existing, synthesised)


def _fill_entries(existing: OdObject, synthesised: OdObject) -> None:
    """Entries of ``existing`` without a default take the value of the same sub-index of ``synthesised``."""
    for sub, e in synthesised.entries.items():
        target = existing.entries.get(sub)
        if target is not None and target.default is None and target.datatype is not None and target.datatype.bits:
            value = e.default_value
            try:
                target.default = target.encode(value)
            except Exception:  # an ESI entry too small for the value keeps no default (reported by checks)
                target.default = None


#: 6502h bit → 6060h value (CiA-402: pp, vl, pv, tq, reserved, hm, ip, csp, csv, cst)
MODE_BITS = {0: 1, 1: 2, 2: 3, 3: 4, 5: 6, 6: 7, 7: 8, 8: 9, 9: 10}


def supported_modes_of(od: ObjectDictionary) -> tuple[int, ...]:
    """Modes from the 6502h default (CiA-402 bits), else from a 6060h enumeration, else ()."""
    e = od.entry(0x6502, 0)
    value = e.default_value if e is not None else None
    if isinstance(value, int) and value:
        return tuple(mode for bit, mode in MODE_BITS.items() if value >> bit & 1)
    mode_entry = od.entry(0x6060, 0)
    if mode_entry is not None and mode_entry.enum:
        return tuple(sorted(k for k in mode_entry.enum if k != 0))
    return ()


def generic_rules(device: Device) -> FamilyRules:
    """Rules derived from an ESI: the mapping objects present, Fixed PDOs, CoE PdoAssign/PdoConfig flags."""
    coe = device.mailbox.coe if device.mailbox is not None else None
    rx = _all_pdos(device, Direction.RX)
    tx = _all_pdos(device, Direction.TX)
    od = device.dictionary
    rx_idx = sorted({p.index for p in rx} | {i for i in od.indices() if 0x1600 <= i <= 0x17FF})
    tx_idx = sorted({p.index for p in tx} | {i for i in od.indices() if 0x1A00 <= i <= 0x1BFF})
    any_fixed = any(p.fixed for p in (*rx, *tx))
    all_fixed = bool(rx or tx) and all(p.fixed for p in (*rx, *tx))
    entries = [o.max_subindex for o in od if 0x1600 <= o.index <= 0x1BFF and o.entries]
    sm_rx = device.process_sm(Direction.RX)
    sm_tx = device.process_sm(Direction.TX)
    modes = supported_modes_of(od)
    notes = [f"derived from the ESI {device.source or device.type_name}"]
    if any_fixed:
        notes.append("some PDOs are Fixed: their mapping cannot be changed")
    if sm_rx is not None and sm_rx.max_size:
        notes.append(f"SM{sm_rx.number} holds at most {sm_rx.max_size} bytes of outputs")
    if sm_tx is not None and sm_tx.max_size:
        notes.append(f"SM{sm_tx.number} holds at most {sm_tx.max_size} bytes of inputs")
    return FamilyRules(
        family="generic",
        vendor_id=device.vendor_id,
        rx_mapping_indices=tuple(rx_idx),
        tx_mapping_indices=tuple(tx_idx),
        max_pdo_entries=max(entries) if entries else None,
        assign_writable=bool(coe and coe.pdo_assign),
        mapping_writable=bool(coe and coe.pdo_config) and not all_fixed,
        dummy_indices=frozenset(range(1, 8)),
        supported_modes=modes,
        notes=tuple(notes),
    )


__all__ = ["MODE_BITS", "SM_TYPE", "complete_generic", "generic_rules", "init_cmds", "plug_default_modules",
           "supported_modes_of"]


def init_cmds(device: Device) -> list[InitCmd]:
    """The device's mailbox init commands and those of each slot's default module, as the device runs.

    Slot k (0-based) moves the index of a module command whose ``Index`` has ``DependOnSlot`` by
    k × SlotIndexIncrement (Copley's XE2: 6060h of the axis-B module is 6860h); a device command marked
    ``OverwrittenByModule`` gives way where a module command writes the same object (ETG.2000).
    """
    from_modules: list[InitCmd] = []
    for k, slot, module in _default_modules(device):
        for c in module.init_cmds:
            q = copy.deepcopy(c)
            if c.depend_on_slot:
                q.index = _shift(c.index, k * (slot.slot_index_increment or 0))
            from_modules.append(q)
    own = list(device.mailbox.init_cmds) if device.mailbox is not None else []
    written = {(c.index, c.subindex) for c in from_modules}
    return [c for c in own if not (c.overwritten_by_module and (c.index, c.subindex) in written)] + from_modules
