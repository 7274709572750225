"""The EtherCAT side of a device as its object dictionary's defaults describe it.

Shared by the built-in families (``ecattool.profiles``) and the CANopen EDS reader (``ecattool.esi.eds``): the
PDOs that the default values of the mapping objects and of 1C12h/1C13h describe, and the sync manager, FMMU and
DC layout that ecattool gives a device whose description has none (docs/decisions.md, "Sync managers").
"""

from __future__ import annotations

from collections.abc import Iterable

from ecattool.esi.model import Direction, Pdo, PdoEntry, SyncManager
from ecattool.od.model import ObjectCode, ObjectDictionary


def default_int(od: ObjectDictionary, index: int, sub: int) -> int:
    e = od.entry(index, sub)
    v = e.default_value if e is not None else None
    return int(v) if isinstance(v, int) else 0


def entry_label(od: ObjectDictionary, index: int, sub: int) -> tuple[str, str]:
    """(name, type name) of a mapped object as a PDO entry shows it: ``Statusword`` or ``Digital outputs/Bit mask``."""
    obj = od.get(index)
    target = obj.entries.get(sub) if obj is not None else None
    if obj is None or target is None:
        return "", ""
    if obj.object_code is ObjectCode.VAR or len(obj.entries) == 1:
        return obj.name, target.type_name
    return f"{obj.name}/{target.name}", target.type_name


def pdos_from_dictionary(od: ObjectDictionary, direction: Direction, indices: Iterable[int], sm: int) -> list[Pdo]:
    """The PDOs described by the default values of the mapping objects and of 1C12h/1C13h."""
    assign = direction.assign_index
    n_assigned = default_int(od, assign, 0)
    assigned = {default_int(od, assign, s) for s in range(1, n_assigned + 1)}
    pdos = []
    for index in indices:
        obj = od.get(index)
        if obj is None:
            continue
        entries = []
        for s in range(1, default_int(od, index, 0) + 1):
            pe = PdoEntry.from_mapping_value(default_int(od, index, s))
            pe.name, pe.data_type = entry_label(od, pe.index, pe.subindex)
            entries.append(pe)
        pdos.append(Pdo(direction, index, obj.name, entries, sm=sm if index in assigned else None))
    return pdos


def standard_sync_managers(rx_bytes: int, tx_bytes: int, rx_max: int, tx_max: int, mbx: int = 128) -> list[SyncManager]:
    """SM0/SM1 mailbox and SM2/SM3 process data at the usual ET1100 addresses (decision "Profiles: SM layout")."""
    return [
        SyncManager(0, "MBoxOut", 0x1000, mbx, mbx, mbx, 0x26),
        SyncManager(1, "MBoxIn", 0x1080, mbx, mbx, mbx, 0x22),
        SyncManager(2, "Outputs", 0x1100, rx_bytes, 0, rx_max, 0x64),
        SyncManager(3, "Inputs", 0x1400, tx_bytes, 0, tx_max, 0x20),
    ]


STANDARD_FMMUS = (("Outputs", 2), ("Inputs", 3), ("MBoxState", None))
DC_FREERUN = ("FreeRun", "Free Run (SM-synchronous / no DC)", 0)
DC_SYNC0 = ("DC", "DC SYNC0", 0x0300)


__all__ = ["DC_FREERUN", "DC_SYNC0", "STANDARD_FMMUS", "default_int", "entry_label", "pdos_from_dictionary",
           "standard_sync_managers"]
