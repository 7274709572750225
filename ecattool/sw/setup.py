"""The setup table as named parameters: show, patch (keeping every integrity word right) and diff.

Sections 1 and 2 are self-describing (16-bit pairs, 32-bit triples); section 3 needs ``parameters.cfg``
for the size of each value. Values are encoded exactly: integers by range, FIXED (16.16) through
:class:`fractions.Fraction` rounded to the nearest step of 1/65536. FLOAT and DOUBLE values are shown but
not patched: the table stores them in base SI units while ``parameters.cfg`` prints display units (e.g.
``L`` 2.1991 mH is stored as 0.0021991), and the conversion for each parameter is not in the evidence.
"""

from __future__ import annotations

import re
import struct
from dataclasses import dataclass
from fractions import Fraction
from typing import Any

from ecattool.errors import InputError, Location
from ecattool.od.numbers import parse_fraction, parse_int
from ecattool.sw.image import SwImage
from ecattool.sw.layout import SetupEntry, SetupTable, decode_section3, fix_integrity, setup_table
from ecattool.sw.params import TYPE_WORDS, Parameter, ParameterTable

_RANGES = {
    "INT": (-0x8000, 0x7FFF),
    "UINT": (0, 0xFFFF),
    "LONG": (-0x8000_0000, 0x7FFF_FFFF),
    "ULONG": (0, 0xFFFF_FFFF),
}
#: type assumed for entries of sections 1 and 2 when no parameters.cfg names them
_SECTION_TYPE = {1: "UINT", 2: "ULONG"}


@dataclass(frozen=True, slots=True)
class SetupValue:
    entry: SetupEntry
    name: str | None
    type: str
    value: Any  # int, Fraction (FIXED) or float (FLOAT/DOUBLE, stored SI value)
    unit: str = ""

    def to_json(self) -> dict[str, Any]:
        v = self.value
        return {
            "section": self.entry.section,
            "address": self.entry.address,
            "name": self.name,
            "type": self.type,
            "raw": self.entry.raw,
            "value": float(v) if isinstance(v, Fraction) else v,
            "unit": self.unit,
        }


def _words_to_bytes(words: tuple[int, ...]) -> bytes:
    return struct.pack(f"<{len(words)}H", *words)


def decode(ptype: str, words: tuple[int, ...]) -> Any:
    raw = sum(w << (16 * i) for i, w in enumerate(words))
    if ptype == "INT":
        return raw - 0x10000 if raw & 0x8000 else raw
    if ptype == "LONG":
        return raw - 0x1_0000_0000 if raw & 0x8000_0000 else raw
    if ptype == "FIXED":
        signed = raw - 0x1_0000_0000 if raw & 0x8000_0000 else raw
        return Fraction(signed, 0x10000)
    if ptype == "FLOAT":
        return struct.unpack("<f", _words_to_bytes(words))[0]
    if ptype == "DOUBLE":
        return struct.unpack("<d", _words_to_bytes(words))[0]
    return raw


def format_value(ptype: str, value: Any) -> str:
    if isinstance(value, Fraction):
        return f"{float(value):.5f}".rstrip("0").rstrip(".")
    if isinstance(value, float):
        return f"{value:.8g}"
    return str(value)


def encode(ptype: str, text: str | int, name: str, location: Location | None = None) -> tuple[int, ...]:
    """``text`` as the words of a ``ptype`` value; InputError for a value out of range or not exact."""
    nwords = TYPE_WORDS[ptype]
    s = str(text).strip()
    if ptype in ("FLOAT", "DOUBLE"):
        raise InputError(
            f"{name} is a {ptype}: the setup table stores it in SI base units and parameters.cfg shows display "
            "units; ecattool does not guess the conversion, so it cannot be patched", location)
    if ptype == "FIXED":
        if s[:2].lower() in ("0x", "#x"):
            raw = parse_int(s, location, f"{name} value")
            if not 0 <= raw <= 0xFFFF_FFFF:
                raise InputError(f"{name}: raw FIXED value {s} does not fit 32 bits", location)
        else:
            try:
                exact = parse_fraction(s, location, f"{name} value")
            except InputError:
                raise InputError(f"{name}: {s[:40]!r} is not a number (FIXED 16.16, e.g. 3.18311 or 0x00032EE0)",
                                 location) from None
            scaled = exact * 0x10000
            raw = round(scaled)
            if not -0x8000_0000 <= raw <= 0x7FFF_FFFF:
                raise InputError(f"{name}: {s} is outside the FIXED range -32768..32767.99998", location)
            raw &= 0xFFFF_FFFF
    else:
        value = parse_int(s, location, f"{name} value")
        lo, hi = _RANGES[ptype]
        unsigned_hi = (1 << (16 * nwords)) - 1
        if not lo <= value <= hi and not (s[:2].lower() in ("0x", "#x") and 0 <= value <= unsigned_hi):
            raise InputError(f"{name}: {value} is outside the {ptype} range {lo}..{hi}", location)
        raw = value & unsigned_hi
    return tuple((raw >> (16 * i)) & 0xFFFF for i in range(nwords))


def _entries(table: SetupTable, params: ParameterTable | None) -> list[SetupEntry]:
    entries = list(table.entries)
    if params is not None:
        entries += decode_section3(table, params)
    return entries


def setup_values(image: SwImage, params: ParameterTable | None = None) -> tuple[SetupTable, list[SetupValue]]:
    """The setup table and its values, named and typed where ``params`` knows the address."""
    table = setup_table(image)
    out: list[SetupValue] = []
    for e in _entries(table, params):
        p = params.by_address(e.address) if params else None
        ptype = p.type if p is not None and TYPE_WORDS[p.type] == len(e.words) else _SECTION_TYPE.get(e.section, "UINT")
        out.append(SetupValue(e, p.name if p else None, ptype, decode(ptype, e.words), p.unit if p else ""))
    return table, out


def _resolve(key: str, params: ParameterTable | None, location: Location | None) -> tuple[int, Parameter | None]:
    k = key.strip()
    if params is not None:
        p = params.by_name(k)
        if p is not None:
            return p.address, p
    if k[:2].lower() in ("0x", "#x") or re.fullmatch(r"[0-9A-Fa-f]+[hH]", k):
        address = parse_int(k, location, "address")
        return address, params.by_address(address) if params else None
    if params is None:
        raise InputError(f"{k!r}: naming parameters needs --parameters parameters.cfg (or give an address like 0x0252)", location)
    raise InputError(f"{k!r} is not a parameter of {params.source or 'the parameter file'}", location)


def patch(image: SwImage, assignments: list[tuple[str, str]], params: ParameterTable | None = None,
          locations: list[Location | None] | None = None) -> SwImage:
    """Set setup-table values (``NAME`` or ``0xADDR`` = value) and recompute every integrity word.

    Only variables the table already holds can be changed: which variables a setup table must contain,
    and in what order, is decided by EasyMotion Studio and is not in the evidence.
    """
    table = setup_table(image)
    entries = {e.address: e for e in _entries(table, params)} if params else {e.address: e for e in table.entries}
    changes: dict[int, int] = {}
    for n, (key, text) in enumerate(assignments):
        loc = locations[n] if locations else None
        address, p = _resolve(key, params, loc)
        label = p.name if p else f"0x{address:04X}"
        e = entries.get(address)
        if e is None:
            hint = "" if params else " (section 3 variables need --parameters)"
            raise InputError(f"{label} (0x{address:04X}) is not in the setup table{hint}; ecattool changes only "
                             "variables the table already holds", loc)
        ptype = p.type if p else _SECTION_TYPE[e.section]
        if TYPE_WORDS[ptype] != len(e.words):
            raise InputError(f"{label} is a {ptype} ({TYPE_WORDS[ptype]} words) but the table stores "
                             f"{len(e.words)} word(s) for 0x{address:04X}", loc)
        words = encode(ptype, text, label, loc)
        for i, w in enumerate(words):
            changes[table.block.start + e.offset + i] = w
    return fix_integrity(image.with_words(changes))


@dataclass(frozen=True, slots=True)
class Difference:
    address: int
    a: int | None
    b: int | None
    name: str | None = None  # a setup variable, when the difference is inside the setup table
    kind: str = "word"  # "word" or "parameter"
    type: str | None = None  # the variable's type where parameters.cfg names it (then a_value/b_value)
    a_value: str | None = None  # decoded as ``sw show`` shows it (FIXED 16.16 as a decimal, signed types signed)
    b_value: str | None = None

    def to_json(self) -> dict[str, Any]:
        out = {"kind": self.kind, "address": self.address, "name": self.name, "a": self.a, "b": self.b}
        if self.type is not None:
            out.update(type=self.type, a_value=self.a_value, b_value=self.b_value)
        return out


def diff(a: SwImage, b: SwImage, params: ParameterTable | None = None) -> list[Difference]:
    """Differences by EEPROM address; where both images have a setup table, by setup variable instead."""
    out: list[Difference] = []
    covered: set[int] = set()
    ta: SetupTable | None
    tb: SetupTable | None
    try:
        ta, tb = setup_table(a), setup_table(b)
    except InputError:
        ta = tb = None
    if ta is not None and tb is not None:
        va = {v.entry.address: v for v in setup_values(a, params)[1]}
        vb = {v.entry.address: v for v in setup_values(b, params)[1]}
        for address in sorted(set(va) | set(vb)):
            x, y = va.get(address), vb.get(address)
            if x is None or y is None or x.entry.words != y.entry.words:
                either = x if x is not None else y
                assert either is not None  # the address comes from va or vb
                typed = params is not None and either.type in TYPE_WORDS
                out.append(Difference(address, x.entry.raw if x else None, y.entry.raw if y else None, either.name,
                                      "parameter", either.type if typed else None,
                                      format_value(x.type, x.value) if typed and x else None,
                                      format_value(y.type, y.value) if typed and y else None))
        for t in (ta, tb):
            covered.update(range(t.block.start, t.block.end + 1))
    wa, wb = a.words(), b.words()
    for address in sorted(set(wa) | set(wb)):
        if address in covered:
            continue
        if wa.get(address) != wb.get(address):
            out.append(Difference(address, wa.get(address), wb.get(address)))
    if ta is not None and tb is not None:
        if ta.config_id != tb.config_id:
            out.insert(0, Difference(ta.block.start + 1, ta.config_id, tb.config_id, "configuration id", "parameter"))
        if len(ta.section3) and ta.section3 != tb.section3 and params is None:
            out.append(Difference(ta.block.start + ta.section3_offset, None, None,
                                  "section 3 (differs; give --parameters to name it)", "parameter"))
    return out
