"""A small hand-built CiA-402 device for the PDO tests (no tests here; imported by tests/pdo/test_pdo_*.py).

Every rule of ``ecattool.pdo.check`` can be triggered on it with a few edits (see ``make_device``).
"""

from __future__ import annotations

from ecattool.esi.model import (
    CoeDetails,
    Device,
    Direction,
    Identity,
    Mailbox,
    Pdo,
    PdoEntry,
    SyncManager,
)
from ecattool.od.model import Access, Entry, ObjectCode, ObjectDictionary, OdObject
from ecattool.od.types import lookup


def _entry(sub: int, name: str, type_name: str, access: str = "rw", pdo: str = "", default: int | None = None,
           bits: int | None = None) -> Entry:
    dt = lookup(type_name)
    size = bits if bits is not None else (dt.bits if dt is not None and dt.bits else 8)
    raw = None
    if default is not None and dt is not None:
        raw = dt.encode(default)
    return Entry(sub, name, dt, size, type_name, access=Access.parse(access), pdo_mapping=pdo, default=raw)


def _var(od: ObjectDictionary, index: int, name: str, type_name: str, access: str = "rw", pdo: str = "",
         bits: int | None = None, category: str = "") -> None:
    obj = OdObject(index, name, ObjectCode.VAR, category=category)
    obj.entries[0] = _entry(0, name, type_name, access, pdo, bits=bits)
    od.add(obj)


def _mapping_object(od: ObjectDictionary, index: int, entries: list[int], size: int = 8) -> None:
    obj = OdObject(index, f"PDO 0x{index:04X}", ObjectCode.RECORD)
    obj.entries[0] = _entry(0, "Number of entries", "USINT", "rw", default=len(entries))
    for k in range(1, size + 1):
        obj.entries[k] = _entry(k, f"Entry {k}", "UDINT", "rw", default=entries[k - 1] if k <= len(entries) else 0)
    od.add(obj)


def _assign_object(od: ObjectDictionary, index: int, pdos: list[int], size: int = 4, access: str = "rw") -> None:
    obj = OdObject(index, f"SM assignment 0x{index:04X}", ObjectCode.ARRAY)
    obj.entries[0] = _entry(0, "Number of entries", "USINT", access, default=len(pdos))
    for k in range(1, size + 1):
        obj.entries[k] = _entry(k, f"PDO {k}", "UINT", access, default=pdos[k - 1] if k <= len(pdos) else 0)
    od.add(obj)


def _pe(index: int, sub: int, bits: int, name: str = "") -> PdoEntry:
    return PdoEntry(index, sub, bits, name)


def make_device(complete_access: bool = True) -> Device:
    """Test drive: Rx 0x1600 (default, SM2), 0x1601; Tx 0x1A00 (default, SM3), 0x1A01 (Fixed, excludes
    0x1A02), 0x1A02; SM2/SM3 at most 16 bytes; CoE with complete access."""
    od = ObjectDictionary()
    _var(od, 0x1008, "Device name", "STRING(8)", "ro")
    _var(od, 0x2000, "Digital input bit", "BOOL", "ro", "T", bits=1)
    _var(od, 0x2001, "Slow parameter", "DINT", "rw", "RT", category="slow")
    _var(od, 0x6040, "Controlword", "UINT", "rw", "R")
    _var(od, 0x6041, "Statusword", "UINT", "ro", "T")
    _var(od, 0x6060, "Modes of operation", "SINT", "rw", "R")
    _var(od, 0x6061, "Modes of operation display", "SINT", "ro", "T")
    _var(od, 0x6064, "Position actual value", "DINT", "ro", "T")
    _var(od, 0x6072, "Max torque", "UINT", "rw")
    _var(od, 0x6077, "Torque actual value", "INT", "ro", "RT")
    _var(od, 0x607A, "Target position", "DINT", "rw", "R")
    _var(od, 0x60B8, "Touch probe function", "UINT", "rw", "RT")
    _var(od, 0x60FF, "Target velocity", "DINT", "rw", "RT")
    arr = OdObject(0x60FE, "Digital outputs", ObjectCode.ARRAY)
    arr.entries[0] = _entry(0, "Number of entries", "USINT", "ro", default=2)
    arr.entries[1] = _entry(1, "Physical outputs", "UDINT", "rw", "R")
    arr.entries[2] = _entry(2, "Bit mask", "UDINT", "rw", "R")
    od.add(arr)
    _mapping_object(od, 0x1600, [0x60400010, 0x607A0020])
    _mapping_object(od, 0x1601, [0x60FE0120])
    _mapping_object(od, 0x1A00, [0x60410010, 0x60640020])
    _mapping_object(od, 0x1A01, [0x60610008], size=1)
    _mapping_object(od, 0x1A02, [0x60770010])
    _assign_object(od, 0x1C12, [0x1600], size=2)
    _assign_object(od, 0x1C13, [0x1A00], size=3)
    rx = [
        Pdo(Direction.RX, 0x1600, "RxPDO 1", [_pe(0x6040, 0, 16, "Controlword"), _pe(0x607A, 0, 32, "Target position")],
            sm=2),
        Pdo(Direction.RX, 0x1601, "RxPDO 2", [_pe(0x60FE, 1, 32, "Physical outputs")]),
    ]
    tx = [
        Pdo(Direction.TX, 0x1A00, "TxPDO 1", [_pe(0x6041, 0, 16, "Statusword"), _pe(0x6064, 0, 32, "Position")], sm=3),
        Pdo(Direction.TX, 0x1A01, "TxPDO 2", [_pe(0x6061, 0, 8, "Modes display")], fixed=True, excludes=[0x1A02]),
        Pdo(Direction.TX, 0x1A02, "TxPDO 3", [_pe(0x6077, 0, 16, "Torque")], excludes=[0x1A01]),
    ]
    sms = [
        SyncManager(0, "MBoxOut", 0x1000, 128),
        SyncManager(1, "MBoxIn", 0x1080, 128),
        SyncManager(2, "Outputs", 0x1100, 6, max_size=16),
        SyncManager(3, "Inputs", 0x1180, 6, max_size=16),
    ]
    mbx = Mailbox(["CoE"], CoeDetails(sdo_info=True, pdo_assign=True, pdo_config=True, complete_access=complete_access))
    return Device(Identity(0xE0000099, 0x1234, 1), "TestDrive", "Test drive", sync_managers=sms, rx_pdos=rx,
                  tx_pdos=tx, dictionary=od, mailbox=mbx, source="test-device")
