"""Shared building blocks of the built-in families: data files → dictionary, dictionary → PDOs and SMs."""

from __future__ import annotations

import json
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from functools import lru_cache
from importlib import resources
from typing import Any

from ecattool.errors import InputError, Location, SelectionError
from ecattool.esi.model import (
    CoeDetails,
    DcOpMode,
    Device,
    Direction,
    Fmmu,
    Identity,
    InitCmd,
    Mailbox,
    Pdo,
    PdoEntry,
    SyncManager,
)
from ecattool.od.model import Access, Entry, ObjectCode, ObjectDictionary, OdObject
from ecattool.od.types import Kind, lookup


@dataclass(frozen=True, slots=True)
class ProductInfo:
    """One model of a family: its key for :func:`ecattool.profiles.load`, identity and known revisions."""

    name: str
    title: str
    product_code: int
    revisions: tuple[str, ...] = ()
    default_revision: str = ""
    notes: str = ""


@dataclass(frozen=True, slots=True)
class ProfileInfo:
    """A built-in drive family."""

    name: str
    family: str
    title: str
    vendor_id: int
    vendor_name: str
    products: tuple[ProductInfo, ...]
    default_product: str
    source: str
    notes: tuple[str, ...] = field(default_factory=tuple)

    def product(self, name: str) -> ProductInfo | None:
        key = name.strip().lower()
        for p in self.products:
            if p.name == key:
                return p
        return None


@lru_cache(maxsize=None)
def load_data(name: str) -> dict[str, Any]:
    """The generated data file ``ecattool/profiles/data/<name>.json`` (parsed once per process)."""
    text = resources.files("ecattool.profiles").joinpath("data", f"{name}.json").read_text(encoding="utf-8")
    data: dict[str, Any] = json.loads(text)
    return data


def make_entry(e: dict[str, Any], source: str, name: str | None = None, default: Any = None) -> Entry:
    """One JSON entry record → :class:`Entry` (typed default bytes, per-state access, PDO flags)."""
    dt = lookup(e["type"])
    bits = int(e["bits"])
    value = e.get("default") if default is None else default
    raw: bytes | None = None
    if value is not None and dt is not None:
        if dt.kind is Kind.STRING:
            raw = str(value).encode("latin-1")
            bits = 8 * len(raw)
        else:
            raw = dt.encode(value) if dt.bits is not None else dt.encode(value, bits)
    enum = {int(k): v for k, v in e.get("enum", {}).items()}
    return Entry(
        subindex=int(e["sub"]),
        name=name or e["name"],
        datatype=dt,
        bit_size=bits,
        type_name=e["type"],
        access=Access.parse(e["access"], None, e.get("write")),
        pdo_mapping=e.get("pdo", ""),
        default=raw,
        minimum=e.get("min"),
        maximum=e.get("max"),
        enum=enum,
        category=e.get("category", ""),
        unit=e.get("unit", ""),
        comment=e.get("comment", ""),
        location=Location(source),
    )


def build_dictionary(
    data: dict[str, Any],
    enabled: Callable[[str], bool] = lambda _req: True,
    defaults: dict[tuple[int, int], Any] | None = None,
    names: Callable[[dict[str, Any]], str | None] = lambda _e: None,
) -> ObjectDictionary:
    """All objects of a data file whose ``requires`` gate is enabled, with ``defaults`` overriding values."""
    od = ObjectDictionary()
    source = f"profile:{data['family']}"
    defaults = defaults or {}
    for o in data["objects"]:
        req = o.get("requires")
        if req and not enabled(req):
            continue
        obj = OdObject(o["index"], o["name"], ObjectCode(o["object_code"]), location=Location(source))
        for e in o["entries"]:
            obj.entries[e["sub"]] = make_entry(e, source, names(e), defaults.get((o["index"], e["sub"])))
        od.add(obj)
    return od


def set_default(od: ObjectDictionary, index: int, sub: int, value: Any) -> None:
    """Replace one entry's default value (encoded with the entry's own type)."""
    e = od.entry(index, sub)
    if e is None or e.datatype is None:
        raise InputError(f"profile data has no object 0x{index:04X}:{sub:02X}")
    if e.datatype.kind is Kind.STRING:
        e.default = str(value).encode("latin-1")
        e.bit_size = 8 * len(e.default)
    else:
        e.default = e.encode(value)


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


def assemble_device(
    *,
    identity: Identity,
    type_name: str,
    name: str,
    od: ObjectDictionary,
    rx_indices: Iterable[int],
    tx_indices: Iterable[int],
    max_pdo_bytes: Callable[[list[Pdo]], int],
    protocols: list[str],
    coe: CoeDetails,
    init_cmds: list[InitCmd] | None = None,
    source: str,
    extra: dict[str, str],
    group: tuple[str, str] = ("Drive", "Drives"),
) -> Device:
    """A complete :class:`Device` from a finished dictionary (PDOs and SM sizes follow its defaults)."""
    rx = pdos_from_dictionary(od, Direction.RX, rx_indices, 2)
    tx = pdos_from_dictionary(od, Direction.TX, tx_indices, 3)
    rx_bytes = (sum(p.bit_size for p in rx if p.sm is not None) + 7) // 8
    tx_bytes = (sum(p.bit_size for p in tx if p.sm is not None) + 7) // 8
    sms = standard_sync_managers(rx_bytes, tx_bytes, max_pdo_bytes(rx), max_pdo_bytes(tx))
    return Device(
        identity=identity,
        type_name=type_name,
        name=name,
        group_type=group[0],
        group_name=group[1],
        physics="YY",
        profile_no=402,
        sync_managers=sms,
        fmmus=[Fmmu(kind, sm) for kind, sm in STANDARD_FMMUS],
        rx_pdos=rx,
        tx_pdos=tx,
        dictionary=od,
        mailbox=Mailbox(protocols=protocols, coe=coe, init_cmds=list(init_cmds or [])),
        dc_opmodes=[DcOpMode(n, d, a) for n, d, a in (DC_FREERUN, DC_SYNC0)],
        source=source,
        extra=extra,
    )


def choose(options: dict[str, Any], key: str | None, default: str, what: str, family: str) -> str:
    """Resolve a product name (case-insensitive) or raise SelectionError listing the valid ones."""
    if key is None or key == "":
        return default
    k = key.strip().lower()
    if k in options:
        return k
    raise SelectionError(f"{family} has no {what} {key!r}; choose one of: {', '.join(sorted(options))}")
