"""Shared building blocks of the built-in families: data files → dictionary, dictionary → PDOs and SMs."""

from __future__ import annotations

import json
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from functools import lru_cache
from importlib import resources
from typing import Any

from ecattool.errors import InputError, Location, SelectionError
from ecattool.esi.derive import (
    DC_FREERUN,
    DC_SYNC0,
    STANDARD_FMMUS,
    pdos_from_dictionary,
    standard_sync_managers,
)
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
        values=frozenset(e["values"]) if "values" in e else None,
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
