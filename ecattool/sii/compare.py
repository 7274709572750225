"""Field-by-field view of an image, and the differences between two images.

String references are resolved to their text, so two images that hold the same strings in a different
order differ only in ``strings`` (the table), not in every field that points into it.
"""

from __future__ import annotations

from typing import Any

from ecattool.sii.model import (
    CategoryType,
    DcCategory,
    FmmuCategory,
    GeneralCategory,
    PdoCategory,
    RawCategory,
    SiiImage,
    StringsCategory,
    SyncMCategory,
    category_name,
    FMMU_USAGE,
)
from ecattool.record import FrozenRecord, Record, set_field


class Difference(FrozenRecord):
    __slots__ = ("field", "a", "b")
    field: str
    a: Any
    b: Any

    def __init__(self, field: str, a: Any, b: Any) -> None:
        set_field(self, "field", field)
        set_field(self, "a", a)
        set_field(self, "b", b)

    def __str__(self) -> str:
        return f"{self.field}: {_show(self.a)} != {_show(self.b)}"

    def to_json(self) -> dict[str, Any]:
        return {"field": self.field, "a": _jsonable(self.a), "b": _jsonable(self.b)}


def _jsonable(v: Any) -> Any:
    if isinstance(v, bytes):
        return v.hex()
    if isinstance(v, tuple):
        return [_jsonable(x) for x in v]
    return v


def _show(v: Any) -> str:
    if v is None:
        return "(absent)"
    if isinstance(v, bytes):
        return v.hex() if len(v) <= 32 else f"{v[:32].hex()}… ({len(v)} bytes)"
    if isinstance(v, int) and not isinstance(v, bool):
        return f"0x{v:X}" if v > 9 else str(v)
    return repr(v)


def _fill(tail: bytes) -> str:
    if not tail:
        return ""
    if tail == b"\xff" * len(tail):
        return f"{len(tail)}x0xFF"
    return tail.hex()


_IDX_FIELDS = {"group_idx": "group", "image_idx": "image", "order_idx": "order", "name_idx": "name",
               "group_name_idx": "group_name", "desc_idx": "desc"}


def _put(out: dict[str, Any], prefix: str, obj: Record, image: SiiImage, skip: tuple[str, ...] = ()) -> None:
    for name in obj._fields:
        if name in skip:
            continue
        v = getattr(obj, name)
        if name in _IDX_FIELDS:
            text = image.string(v)
            out[f"{prefix}.{_IDX_FIELDS[name]}"] = text if text is not None else f"<bad string index {v}>"
        elif name == "extra" and not v:
            continue
        else:
            out[f"{prefix}.{name}"] = v


def flatten(image: SiiImage) -> dict[str, Any]:
    """Every field of the image under a stable dotted name, string references resolved."""
    out: dict[str, Any] = {}
    _put(out, "header", image.header, image)
    out["image.length"] = len(image.to_bytes())
    out["image.categories"] = ",".join(category_name(c.cat_type) for c in image.categories) + (
        ",END" if image.end_marker else "")
    out["image.fill"] = _fill(image.tail)
    seen: dict[str, int] = {}

    def key(base: str) -> str:
        n = seen.get(base, 0) + 1
        seen[base] = n
        return base if n == 1 else f"{base}#{n}"

    counters = {"sm": 0, "dc": 0}

    def numbered(prefix: str, items: list[Any], extra: bytes) -> None:
        for item in items:
            _put(out, f"{prefix}[{counters[prefix]}]", item, image)
            counters[prefix] += 1
        if extra:
            out[key(f"{prefix}.extra")] = extra

    fmmu_i = 0
    for c in image.categories:
        if isinstance(c, StringsCategory):
            k = key("strings")
            out[k] = tuple(c.strings)
            if c.extra:
                out[f"{k}.extra"] = c.extra
        elif isinstance(c, GeneralCategory):
            _put(out, key("general"), c, image)
        elif isinstance(c, FmmuCategory):
            for u in c.usages:
                out[f"fmmu[{fmmu_i}]"] = FMMU_USAGE.get(u, f"0x{u:02X}") or f"unused(0x{u:02X})"
                fmmu_i += 1
        elif isinstance(c, SyncMCategory):
            numbered("sm", c.sync_managers, c.extra)
        elif isinstance(c, DcCategory):
            numbered("dc", c.opmodes, c.extra)
        elif isinstance(c, PdoCategory):
            kind = "txpdo" if c.type == CategoryType.TXPDO else "rxpdo"
            for p in c.pdos:
                pk = key(f"{kind}[0x{p.index:04X}]")
                _put(out, pk, p, image, skip=("index", "entries"))
                out[f"{pk}.entries"] = len(p.entries)
                for j, e in enumerate(p.entries):
                    _put(out, f"{pk}.entry[{j}]", e, image)
            if c.extra:
                out[key(f"{kind}.extra")] = c.extra
        elif isinstance(c, RawCategory):
            out[key(f"cat[{category_name(c.type)}]")] = c.data
    return out


def diff(a: SiiImage, b: SiiImage) -> list[Difference]:
    """Fields whose values differ (present in only one image: the other side is None)."""
    fa, fb = flatten(a), flatten(b)
    keys = list(fa) + [k for k in fb if k not in fa]
    return [Difference(k, fa.get(k), fb.get(k)) for k in keys if fa.get(k) != fb.get(k)]
