"""SDO access typed by a dictionary: one object read or written, every object read into a dictionary snapshot
(``sdo dump``), which ``audit`` and ``esi`` commands compare."""

from __future__ import annotations

from typing import Any

from ecattool.abort import abort_text
from ecattool.errors import InputError, Location, SdoAbort, TargetError
from ecattool.fileio import read_bytes
from ecattool.od.model import EcState, Entry
from ecattool.online.dictionary import Typed, decode, encode
from ecattool.record import Record
from ecattool.target.base import entry_size

SNAPSHOT_FORMAT = "ecattool-dictionary-snapshot"


def address(index: int, subindex: int) -> str:
    return f"0x{index:04X}:{subindex:02X}"


class ReadValue(Record):
    """One object as read: its address, name and type, the bytes and their decoded value, or the abort code."""

    __slots__ = ("index", "subindex", "name", "type_name", "data", "value", "abort")
    index: int
    subindex: int
    name: str
    type_name: str
    data: bytes | None
    value: Any
    abort: int | None

    def __init__(self, index: int, subindex: int, name: str, type_name: str, data: bytes | None, value: Any,
                 abort: int | None = None) -> None:
        self.index = index
        self.subindex = subindex
        self.name = name
        self.type_name = type_name
        self.data = data
        self.value = value
        self.abort = abort

    def to_json(self) -> dict[str, Any]:
        out: dict[str, Any] = {"address": address(self.index, self.subindex), "name": self.name,
                               "type": self.type_name}
        if self.abort is not None:
            out.update(abort=f"0x{self.abort:08X}", abort_text=abort_text(self.abort))
        else:
            out.update(value=self.value, hex=(self.data or b"").hex())
        return out


def size_problem(entry: Entry | None, data: bytes) -> str | None:
    """Why ``data`` cannot be a value of ``entry``'s data type: a type of fixed size (UDINT: 4 octets, BOOL and
    BIT2: 1) answered with another number of octets. None when it fits or the type has no fixed size."""
    dt = entry.datatype if entry is not None else None
    if entry is None or dt is None or dt.bits is None:
        return None
    want = (dt.bits + 7) // 8
    # the size the description gives the entry counts too (an ESI's BitSize that is not its type's, as a few
    # vendor files have: the drive answers by its own description)
    if len(data) == want or (entry.bit_size and len(data) == (entry.bit_size + 7) // 8):
        return None
    return f"answered {len(data)} byte(s), a {entry.type_name} has {want}"


class ValueSizeError(TargetError):
    """A slave's reply whose size is not its object's data type's (a 64-byte or empty "UDINT")."""


def read_value(slave: Any, typed: Typed, index: int, subindex: int, *, keep_aborts: bool = False) -> ReadValue:
    """One object read over SDO and decoded by ``typed``; an abort is raised (or kept, ``keep_aborts``). A reply
    whose size is not the data type's is a :class:`ValueSizeError` naming the slave and the object."""
    e = typed.entry(index, subindex)
    name = e.name if e is not None else ""
    type_name = e.type_name if e is not None else ""
    try:
        data = slave.sdo_upload(index, subindex, size=entry_size(e))
    except SdoAbort as exc:
        if not keep_aborts:
            raise
        return ReadValue(index, subindex, name, type_name, None, None, exc.code)
    wrong = size_problem(e, data)
    if wrong is not None:
        raise ValueSizeError(f"slave {slave.position}: {address(index, subindex)}{' ' + name if name else ''}: "
                             f"{wrong}")
    return ReadValue(index, subindex, name, type_name, data, decode(e, data))


def write_value(slave: Any, typed: Typed, index: int, subindex: int, text: str) -> bytes:
    """Encode ``text`` by the entry's type and download it; returns the bytes sent."""
    data = encode(typed.entry(index, subindex), text, index, subindex)
    slave.sdo_download(index, subindex, data)
    return data


def readable_addresses(typed: Typed, state: EcState) -> list[tuple[int, int]]:
    """Every entry of the dictionary that is readable in ``state`` (sub-index 0 of a record too)."""
    out = []
    for obj in typed.dictionary:
        for e in obj:
            if e.access.readable(state):
                out.append((obj.index, e.subindex))
    return out


def dump(slave: Any, typed: Typed, spec: str) -> dict[str, Any]:
    """A dictionary snapshot of ``slave``: every readable object of its dictionary, value or abort code."""
    if not len(typed.dictionary):
        raise InputError(f"slave {slave.position}: no dictionary types its objects (no library device, built-in "
                         "family or SDO Information); give --library or --device")
    state = slave.state()
    ident = slave.identity()
    objects = {}
    for index, sub in readable_addresses(typed, state):
        v = read_value(slave, typed, index, sub, keep_aborts=True)
        objects[address(index, sub)] = {k: x for k, x in v.to_json().items() if k != "address"}
    return {"format": SNAPSHOT_FORMAT, "version": 1, "target": spec, "position": slave.position,
            "identity": {"vendor_id": ident.vendor_id, "product_code": ident.product_code,
                         "revision": ident.revision, "serial": ident.serial},
            "state": state.value, "dictionary": typed.source, "objects": objects}


def load_snapshot(path: str) -> dict[str, Any]:
    import json  # here: reading one object (sdo read) needs no JSON reader

    try:
        data = json.loads(read_bytes(path))
    except (ValueError, UnicodeDecodeError) as exc:
        raise InputError(f"not a JSON dictionary snapshot: {exc}", Location(path)) from None
    if not isinstance(data, dict) or data.get("format") != SNAPSHOT_FORMAT:
        raise InputError(f"not an ecattool dictionary snapshot (format {SNAPSHOT_FORMAT!r} expected)", Location(path))
    objects = data.get("objects")
    if not isinstance(objects, dict) or not all(isinstance(v, dict) for v in objects.values()):
        raise InputError("the snapshot's 'objects' is not a mapping of 0xIIII:SS to objects", Location(path))
    return data


class SnapshotDifference(Record):
    """One object whose value differs between two snapshots, or that only one of them has."""

    __slots__ = ("address", "name", "a", "b")
    address: str
    name: str
    a: Any
    b: Any

    def __init__(self, address: str, name: str, a: Any, b: Any) -> None:
        self.address = address
        self.name = name
        self.a = a
        self.b = b

    def to_json(self) -> dict[str, Any]:
        return {"address": self.address, "name": self.name, "a": self.a, "b": self.b}

    def __str__(self) -> str:
        return f"{self.address} {self.name}: {self.a!r} -> {self.b!r}"


def _shown(row: dict[str, Any] | None) -> Any:
    if row is None:
        return None
    return f"abort {row['abort']}" if "abort" in row else row.get("value")


def diff_snapshots(a: dict[str, Any], b: dict[str, Any]) -> list[SnapshotDifference]:
    """Objects whose value (or abort) differs between snapshot ``a`` and ``b``, and those only one has."""
    out = []
    objs_a, objs_b = a.get("objects", {}), b.get("objects", {})
    for key in sorted(set(objs_a) | set(objs_b)):
        ra, rb = objs_a.get(key), objs_b.get(key)
        if ra is not None and rb is not None and (ra.get("hex"), ra.get("abort")) == (rb.get("hex"), rb.get("abort")):
            continue
        name = (ra or rb or {}).get("name", "")
        out.append(SnapshotDifference(key, name, _shown(ra), _shown(rb)))
    return out
