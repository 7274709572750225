"""Generate ``ecattool/profiles/data/*.json`` from the manual digests (``objects.csv``/``parameters.csv``).

Run once (and again whenever a reference CSV or a decision below changes)::

    python -m ecattool.profiles._build_data [REFERENCE_DIR]

REFERENCE_DIR defaults to ``../shared/reference`` beside the repository. The generated JSON files are
checked into git; the package reads only them at run time (the reference directory is not shipped).

The CSVs keep the manuals' printed values, misprints included. Every place where this script departs from
the printed value is an explicit entry of an ``OVERRIDES``/``*_FIX`` table below, with the number of the
decision in docs/decisions.md ("Profiles: …") that justifies it.
"""

from __future__ import annotations

import csv
import json
import re
import sys
from collections import OrderedDict
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[2]
DATA = Path(__file__).resolve().parent / "data"

# ---------------------------------------------------------------------------------------------------------
# shared helpers
# ---------------------------------------------------------------------------------------------------------

_TYPES: dict[str, tuple[str, int]] = {
    # technosoft spellings
    "UNSIGNED8": ("USINT", 8), "UNSIGNED16": ("UINT", 16), "UNSIGNED32": ("UDINT", 32), "UNSIGNED48": ("UINT48", 48),
    "INTEGER8": ("SINT", 8), "INTEGER16": ("INT", 16), "INTEGER32": ("DINT", 32), "ULONG32": ("UDINT", 32),
    "USINT8": ("USINT", 8), "FIXED32": ("DINT", 32), "INTERPOLATED MODE DEPENDENT": ("DINT", 32),
    # hdt spellings
    "UINT8": ("USINT", 8), "UINT16": ("UINT", 16), "UINT32": ("UDINT", 32), "INT8": ("SINT", 8),
    "INT16": ("INT", 16), "INT32": ("DINT", 32), "INT64": ("LINT", 64),
    # control techniques spellings (sizes in bytes or bits)
    "1 BYTE": ("USINT", 8), "2 BYTES": ("UINT", 16), "4 BYTES": ("UDINT", 32), "UNSIGNED 8": ("USINT", 8),
    "UNSIGNED 16": ("UINT", 16), "UNSIGNED 32": ("UDINT", 32), "SIGNED 8": ("SINT", 8), "SIGNED 16": ("INT", 16),
    "SIGNED 32": ("DINT", 32), "16 BITS": ("INT", 16), "4 BYTES (32-BIT SIGNED)": ("DINT", 32),
}


def norm_type(text: str) -> tuple[str, int] | None:
    t = text.strip().upper()
    if t in ("VISIBLE STRING", "STR"):
        return ("STRING", 0)
    return _TYPES.get(t)


_NUM = r"[-+]?(?:0x[0-9A-Fa-f]+|[0-9A-Fa-f]+h|\d+(?:\^\d+)?(?:-\d+)?)"


def parse_number(token: str) -> int | None:
    """``0x1A3``, ``1A3h``, ``-2^31``, ``2^31-1``, ``65535``, ``+32767`` → int (None if not a number)."""
    t = token.strip().replace("+", "") if token.strip().startswith("+") else token.strip()
    if not t:
        return None
    neg = t.startswith("-")
    body = t[1:] if neg else t
    m = re.fullmatch(r"(\d+)\^(\d+)(?:-(\d+))?", body)
    if m:
        v: int = int(m.group(1)) ** int(m.group(2)) - int(m.group(3) or 0)
    elif re.fullmatch(r"0x[0-9A-Fa-f]+", body):
        v = int(body, 16)
    elif re.fullmatch(r"[0-9A-Fa-f]+h", body):
        v = int(body[:-1], 16)
    elif re.fullmatch(r"\d+", body):
        v = int(body)
    else:
        return None
    return -v if neg else v


def parse_default(text: str) -> int | None:
    """The first numeric token of a default cell (``0x60400010 (Controlword)`` → 0x60400010)."""
    t = text.strip()
    if not t:
        return None
    first = re.split(r"[\s(\[]", t, maxsplit=1)[0]
    return parse_number(first)


def parse_range(text: str) -> tuple[int | None, int | None]:
    t = text.strip().replace("–", "-").replace("(printed", "#").split("#")[0].strip()
    t = re.sub(r"\(.*?\)", "", t).strip()
    if t.startswith("±"):
        v = parse_number(t[1:])
        return (-v, v) if v is not None else (None, None)
    for sep in (r"\s*\.\.\.\s*", r"\s*\.\.\s*", r"\s+to\s+", r"\s*-\s*(?=\d)", r"\s+or\s+"):
        parts = re.split(sep, t, maxsplit=1)
        if len(parts) == 2:
            lo, hi = parse_number(parts[0]), parse_number(parts[1])
            if lo is not None and hi is not None:
                return lo, hi
    return None, None


#: a decimal-comma number ("0,9500", "0,01"): a display value (decision HDT-6), not a list of values
_DECIMAL_COMMA = re.compile(r"\d,\d")
_LIST_ITEM = r"[-+]?(?:0x[0-9A-Fa-f]+|[0-9A-Fa-f]+h|\d+)"


def _numbers(text: str) -> list[int] | None:
    """``-1, 0, 3`` → [-1, 0, 3]; None unless every comma-separated item is a number."""
    items = [parse_number(x) for x in text.split(",")]
    return None if any(v is None for v in items) else [v for v in items if v is not None]


class RangeSpec:
    """A printed value range as one of three kinds (decision Profiles-2): an interval ``lo..hi``, a single
    value (``lo == hi``: "0, only linear", "fixed to -3") or a value list (``values``: "-1, 0, 3",
    "0..6 (values 0,1,2,5,6)", "0..35 except 15,16,31,32"), whose ``lo``/``hi`` are its smallest and largest
    values."""

    __slots__ = ("lo", "hi", "values")

    def __init__(self, lo: int | None = None, hi: int | None = None, values: list[int] | None = None) -> None:
        self.lo, self.hi, self.values = lo, hi, values

    def __repr__(self) -> str:
        return f"RangeSpec({self.lo}, {self.hi}, {self.values})"

    @property
    def kind(self) -> str:
        if self.values is not None:
            return "values"
        if self.lo is None or self.hi is None:
            return "none"
        return "single" if self.lo == self.hi else "interval"


def parse_range_spec(text: str) -> RangeSpec:
    """The range cell of a manual's table as a :class:`RangeSpec` (interval, single value or value list).

    A decimal comma ("0,8000..0,9900", HDT-6) is a display value of unstated scale: no range. A type name
    before a parenthesised range ("INTEGER8, (-128 to +63)", Technosoft 60C2h:02) gives the parenthesised
    range."""
    t = text.strip().replace("\u2013", "-")
    t = t.replace("(printed", "#").split("#")[0].strip()
    if not t:
        return RangeSpec()
    m = re.search(r"\(values\s+([^)]*)\)", t)
    if m:
        vals = _numbers(m.group(1))
        if vals:
            return RangeSpec(min(vals), max(vals), sorted(vals))
    m = re.fullmatch(r"(.*?)\s+except\s+(.*)", t)
    if m:
        outer = parse_range_spec(m.group(1))
        gone = _numbers(m.group(2))
        if outer.lo is not None and outer.hi is not None and gone and outer.hi - outer.lo <= 4096:
            vals = [v for v in range(outer.lo, outer.hi + 1) if v not in gone]
            return RangeSpec(min(vals), max(vals), vals)
    if _DECIMAL_COMMA.search(t) and not re.search(r",\s", t):
        return RangeSpec()
    if re.fullmatch(rf"{_LIST_ITEM}(?:\s*,\s*{_LIST_ITEM})+", t):
        vals = _numbers(t)
        if vals:
            return RangeSpec(min(vals), max(vals), sorted(set(vals)))
    bare = re.sub(r"\(.*?\)", "", t).strip()
    if re.fullmatch(_LIST_ITEM, bare):
        v = parse_number(bare)
        return RangeSpec(v, v)
    lo, hi = parse_range(bare)
    if lo is None and re.fullmatch(r"[A-Za-z]+\d*,?", bare):  # a type name, then the range in brackets
        for inner in re.findall(r"\(([^)]*)\)", t):
            lo, hi = parse_range(inner)
            if lo is not None:
                break
    return RangeSpec(lo, hi)


def entry(sub: int, name: str, typ: str, bits: int, access: str, pdo: str = "", default: Any = None,
          lo: int | None = None, hi: int | None = None, unit: str = "", comment: str = "",
          write: str | None = None, category: str = "", values: list[int] | None = None) -> dict[str, Any]:
    e: dict[str, Any] = OrderedDict(sub=sub, name=name, type=typ, bits=bits, access=access)
    if write:
        e["write"] = write
    if pdo:
        e["pdo"] = pdo
    if default is not None:
        e["default"] = default
    if lo is not None:
        e["min"] = lo
    if hi is not None:
        e["max"] = hi
    if values is not None:
        e["values"] = values
    if unit:
        e["unit"] = unit
    if category:
        e["category"] = category
    if comment:
        e["comment"] = comment
    return e


def pdo_dirs(mappable: bool, access: str) -> str:
    """ESI convention: a mappable writable object is RxPDO-mappable, a readable one TxPDO-mappable."""
    if not mappable:
        return ""
    return ("R" if access in ("rw", "wo") else "") + ("T" if access in ("rw", "ro", "const") else "")


def type_range(typ: str, bits: int) -> tuple[int | None, int | None]:
    if typ in ("USINT", "UINT", "UDINT", "UINT48", "ULINT"):
        return 0, (1 << bits) - 1
    if typ in ("SINT", "INT", "DINT", "LINT"):
        return -(1 << (bits - 1)), (1 << (bits - 1)) - 1
    return None, None


def clean_range(typ: str, bits: int, lo: int | None, hi: int | None) -> tuple[int | None, int | None]:
    """Drop a printed range that only restates the type (keeps the JSON small) or exceeds it."""
    tlo, thi = type_range(typ, bits)
    if lo is None or hi is None or tlo is None or thi is None:
        return None, None
    if (lo, hi) == (tlo, thi):
        return None, None
    if lo < tlo or hi > thi or lo > hi:
        return None, None
    return lo, hi


def clean_spec(typ: str, bits: int, spec: RangeSpec) -> tuple[int | None, int | None, list[int] | None]:
    """:func:`clean_range` for a :class:`RangeSpec`: (min, max, value list or None)."""
    lo, hi = clean_range(typ, bits, spec.lo, spec.hi)
    if spec.values is None:
        return lo, hi, None
    tlo, thi = type_range(typ, bits)
    if tlo is None or thi is None or not all(tlo <= v <= thi for v in spec.values):
        return None, None, None
    return spec.lo, spec.hi, list(spec.values)


def fit_default(typ: str, bits: int, value: int | None) -> int | None:
    """Re-interpret a hex default as two's complement for signed types (``0x80000000`` in an INTEGER32)."""
    if value is None:
        return None
    tlo, thi = type_range(typ, bits)
    if tlo is None or thi is None:
        return value
    if typ in ("SINT", "INT", "DINT", "LINT") and thi < value < (1 << bits):
        value -= 1 << bits
    if not tlo <= value <= thi:
        return None
    return value


def finish(family: str, source: str, objects: dict[int, dict[str, Any]], csv_rows: int, extra: dict[str, Any]) -> dict[str, Any]:
    out: dict[str, Any] = OrderedDict(family=family, source=source, csv_rows=csv_rows)
    out.update(extra)
    objs = []
    for idx in sorted(objects):
        o = objects[idx]
        subs = o["entries"]
        if o["object_code"] != "VAR" and subs:
            # every ARRAY/RECORD gets a sub-index 0 "number of entries" whose default is its highest
            # sub-index when the manual prints none (decision "Profiles: sub-index 0")
            top = max(subs)
            if 0 not in subs:
                subs[0] = entry(0, "Number of entries", "USINT", 8, "ro", default=top,
                                comment="not printed; highest sub-index (decision Profiles-1)")
            elif subs[0].get("default") is None:
                subs[0]["default"] = top
        o["entries"] = [o["entries"][s] for s in sorted(o["entries"])]
        objs.append(o)
    out["objects"] = objs
    return out


def new_object(index: int, name: str, code: str, section: str) -> dict[str, Any]:
    return OrderedDict(index=index, name=name, object_code=code, section=section, entries={})


# ---------------------------------------------------------------------------------------------------------
# Technosoft iPOS (P091.064.UM.0524)
# ---------------------------------------------------------------------------------------------------------

#: firmware gates (digest "Firmware families"; decisions "Profiles: Technosoft firmware gates")
TS_REQUIRES: dict[int, str] = {
    **{i: "cia402-2" for i in (0x608F, 0x6091, 0x6092, 0x6096, 0x60A2, 0x60A8, 0x60A9, 0x60AA, 0x60AB, 0x210F, 0x2110)},
    **{i: "cia402-obsolete" for i in (0x6089, 0x608A, 0x608B, 0x608C, 0x608D, 0x608E, 0x206F, 0x2070, 0x2071)},
    **{i: "F515K+" for i in (0x606D, 0x606E, 0x6075, 0x6087, 0x6080)},
    0x20A0: "F515K/FA00C+",
    **{i: "F515x" for i in (0x2009, 0x208B, 0x208C, 0x2091, 0x2092, 0x2086)},
    0x2112: "FA0xx",
    **{i: "FA00G+" for i in (0x2113, 0x2114, 0x2115)},
    **{i: "F515J+" for i in (0x210D, 0x210E)},
    0x210C: "F515F+",
}

#: decided departures from the printed attributes: (index, sub) -> fields to replace
TS_FIX: dict[tuple[int, int], dict[str, Any]] = {
    (0x1018, 0): {"default": 4, "comment": "printed default 1; 4 sub-indices exist (decision TS-1)"},
    (0x1C00, 4): {"default": 4, "comment": "printed default 3; value list says 4 = process data input (decision TS-2)"},
    (0x1C12, 0): {"access": "rw", "min": 0, "max": 4, "comment": "printed RO 1-4; written 0/n in Pre-Op (decision TS-3)"},
    (0x1C13, 0): {"access": "rw", "min": 0, "max": 4, "comment": "printed RO; written 0/n in Pre-Op (decision TS-3)"},
    (0x2001, 0): {"access": "rw", "comment": "printed RO; it is the user's EMCY mask (decision TS-6)"},
    (0x20A0, 0): {"pdo": ""},
    (0x607E, 0): {"max": 255},
    (0x2012, 0): {"min": None, "max": None},
    (0x201E, 0): {"min": None, "max": None},
    (0x2086, 0): {"min": None, "max": None},
    (0x208A, 0): {"min": None, "max": None},
    (0x2102, 0): {"min": 0, "max": 1},
    (0x2073, 0): {"min": 1, "max": None},
    (0x2108, 3): {"type": "INT", "min": None, "max": None,
                  "comment": "no type printed and a range \"0 -32767\"; Technosoft's iPOS EDS v1.04 "
                             "declares INTEGER16 (a filtered current is signed) (decision TS-7)"},
}


def _ts_split_name(name: str) -> tuple[str, str]:
    if ": " in name:
        a, _, b = name.partition(": ")
        return a.strip(), b.strip()
    return name.strip(), name.strip()


def _ts_variant(text: str, section_prefix: str) -> str:
    """``A [5.2.2] / B [5.1.10]`` → the part tagged with a section starting with ``section_prefix``."""
    for part in text.split(" / "):
        m = re.search(r"\[([\d.]+)\]", part)
        if m and m.group(1).startswith(section_prefix):
            return re.sub(r"\s*\[[\d.]+\]", "", part).strip()
    return re.sub(r"\s*\[[\d.]+\]", "", text.split(" / ")[0]).strip()


def build_technosoft(ref: Path) -> dict[str, Any]:
    rows = list(csv.DictReader((ref / "technosoft" / "objects.csv").open(encoding="utf-8")))
    objects: dict[int, dict[str, Any]] = {}
    for r in rows:
        index = int(r["index"], 16)
        sub = int(r["subindex"])
        oname, ename = _ts_split_name(r["name"])
        code = r["object_code"] or "VAR"
        obj = objects.get(index)
        if obj is None:
            obj = objects[index] = new_object(index, oname, code, r["section"])
            if index in TS_REQUIRES:
                obj["requires"] = TS_REQUIRES[index]
        if sub > 0 and obj["object_code"] == "VAR":
            obj["object_code"] = "ARRAY" if index == 0x2113 else "RECORD"  # decision TS-7 (20A0h, 2113h)
        # names: the CiA-402 (obsolete) vs CiA-402-2 variants of 6093h/6094h/6097h
        variants = {}
        if "[5.1." in ename and "[5.2." in ename:
            variants["name_obsolete"] = _ts_variant(ename, "5.1").split(": ")[-1]
            ename = _ts_variant(ename, "5.2")
        ename = re.sub(r"\s*\[[\d.]+\]", "", ename)
        # data type
        nt = norm_type(r["data_type"])
        if nt is None:
            counts = "entries" in r["name"].lower() or "number of sub" in r["name"].lower()
            if sub == 0 and index not in (0x1009,) and (obj["object_code"] != "VAR" or counts):
                nt = ("USINT", 8)
            elif index in (0x1C12, 0x1C13):
                nt = ("UINT", 16)
            elif index == 0x1009:
                nt = ("STRING", 0)
            else:
                nt = ("UINT", 16)  # the reserved 2113h sub-indices (decision TS-7); 2108h.3 is fixed in TS_FIX
        typ, bits = nt
        # access
        acc = (r["access"] or "").strip().lower()
        if not acc:
            acc = "rw" if (index in (0x1C12, 0x1C13) and sub > 0) or (index == 0x2113) else "ro"
        write = None
        if index in (0x1C12, 0x1C13) or 0x1600 <= index <= 0x1603 or 0x1A00 <= index <= 0x1A03:
            write = "PreOP"  # decision TS-4
        # PDO mapping: "Yes"/"Possible" → mappable (directions from access); sub 0 counts never
        pm = r["pdo_mapping"].strip().lower()
        mappable = pm.startswith("yes") or pm.startswith("possible")
        if sub == 0 and obj["object_code"] != "VAR":
            mappable = False
        # default
        default: Any
        if typ == "STRING":
            d = r["default"].strip()
            default = d if d and d.lower() not in ("no", "-", "product dependent") else None
            bits = 8 * len(default) if default else 0
        else:
            default = fit_default(typ, bits, parse_default(r["default"]))
        lo, hi, values = clean_spec(typ, bits, parse_range_spec(r["value_range"])) if typ != "STRING" \
            else (None, None, None)
        e = entry(sub, ename, typ, bits, acc, "", default, lo, hi, r["units"].strip(" -"), "",
                  write=write, values=values)
        e["pdo"] = pdo_dirs(mappable, acc)
        e.update(variants)
        note = r["notes"].strip()
        e["comment"] = f"§{r['section']}" + (f"; {note}" if note else "")
        for k, v in TS_FIX.get((index, sub), {}).items():
            if k == "comment":
                e["comment"] = f"§{r['section']}; {v}"
            elif v is None:
                e.pop(k, None)
            else:
                e[k] = v
        if not e["pdo"]:
            e.pop("pdo")
        obj["entries"][sub] = OrderedDict((k, v) for k, v in e.items())
    # mapping objects have sub-indices 1..8 (§2.4 step 4); untabulated ones default to 0 (decision TS-5)
    for index in (*range(0x1600, 0x1604), *range(0x1A00, 0x1A04)):
        obj = objects[index]
        obj["entries"][0]["max"] = 8
        for sub in range(1, 9):
            if sub not in obj["entries"]:
                obj["entries"][sub] = entry(sub, f"{sub}. mapped object", "UDINT", 32, "rw", default=0,
                                            write="PreOP", comment="§2.4 (sub-indices 1-8); not tabulated")
        obj["name"] = obj["name"].replace("Parameters", "Parameter")
    objects[0x6093]["name"] = "Position factor"
    # assignment slots not tabulated: 1C12h.n = 1600h+n-1, 1C13h.n = 1A00h+n-1 (decision TS-5)
    for index, base in ((0x1C12, 0x1600), (0x1C13, 0x1A00)):
        for sub in range(1, 5):
            e = objects[index]["entries"][sub]
            e.setdefault("default", base + sub - 1)
            e["min"], e["max"] = base, base + 3
            e["access"] = "rw"
            e["write"] = "PreOP"
            if e["name"].startswith("PDO Mapping object index of assigned"):
                e["name"] = f"{'Rx' if index == 0x1C12 else 'Tx'}PDO assigned (slot {sub})"
    # 1009h exists only in Appendix A: an empty visible string
    objects[0x1009]["entries"][0].update(type="STRING", bits=0, access="const")
    objects[0x1008]["entries"][0]["bits"] = 8 * len("iPOS")
    # modes of operation values (§4.2.3, decision TS-8)
    modes = {1: "Profile position", 3: "Profile velocity", 4: "Profile torque", 6: "Homing",
             7: "Interpolated position", 8: "Cyclic synchronous position", 9: "Cyclic synchronous velocity",
             10: "Cyclic synchronous torque", -1: "Electronic gearing (EGEAR)", -2: "Electronic camming (ECAM)"}
    for idx in (0x6060, 0x6061):
        objects[idx]["entries"][0]["enum"] = {str(k): v for k, v in modes.items()}
    return finish("technosoft-ipos", "Technosoft iPOS CoE Programming P091.064.UM.0524", objects, len(rows), {})


# ---------------------------------------------------------------------------------------------------------
# HDT Tomcat / DGFOX / NTT ("DS-301 protocol CANopen – EtherCAT" Rev 4.0)
# ---------------------------------------------------------------------------------------------------------

HDT_NAMES = {
    0x1003: "Pre-defined error field", 0x1010: "Store parameters", 0x1018: "Identity object",
    0x1200: "Server SDO parameter", **{0x1400 + i: f"RPDO{i + 1} communication parameter" for i in range(4)},
    **{0x1800 + i: f"TPDO{i + 1} communication parameter" for i in range(4)},
    **{0x1600 + i: f"RPDO{i + 1} mapping parameter" for i in range(4)},
    **{0x1A00 + i: f"TPDO{i + 1} mapping parameter" for i in range(4)},
    0x1C00: "Sync manager communication type", 0x1C12: "RxPDO assign", 0x1C13: "TxPDO assign",
    0x1C32: "SM output parameter", 0x1C33: "SM input parameter", 0x2055: "Filter time inputs 0..7",
    0x2056: "Filter time inputs 8..10", 0x2059: "Drive's name", 0x2072: "Generic data words",
    0x208B: "Output time outs", 0x209D: "Frequency jumps", 0x209E: "Frequency jump deltas",
    0x20A7: "V/Hz ramp frequencies", 0x20A8: "V/Hz ramp voltages", 0x6046: "vl velocity min max amount",
    0x6048: "vl velocity acceleration", 0x6049: "vl velocity deceleration", 0x604C: "vl dimension factor",
    0x607D: "Software position limit", 0x6093: "Position factor", 0x6094: "Velocity encoder factor",
    0x6097: "Acceleration factor", 0x6099: "Homing speeds", 0x60C1: "Interpolation data record",
    0x60C2: "Interpolation time period",
}

HDT_FIX: dict[tuple[int, int], dict[str, Any]] = {
    (0x1018, 0): {"default": 3, "max": 3, "comment": "printed 0..1 / 1; sub-indices 1..3 exist (decision HDT-1)"},
    (0x1018, 2): {"default": 0x000C0458, "comment": "printed 00C0458h (7 digits; decision HDT-2)"},
    (0x1018, 3): {"default": 0},
    (0x1A03, 0): {"default": 1, "comment": "printed blank; one default entry (ambiguity 16)"},
    (0x1001, 0): {"pdo": "T", "comment": "Map No as printed but mapped by default in 1A00h (decision HDT-3)"},
    (0x6093, 0): {"access": "ro"},
    (0x1C00, 0): {"default": 4},
    (0x1005, 0): {"default": 0x80, "comment": "type/default not printed; Caliper screenshot 00000080h (ambiguity 7)"},
    # dimension indices printed INT8 holding ACh/A4h/A3h: kept as the raw byte, typed UNSIGNED8 as in
    # CiA-402 (decision HDT-8)
    (0x608A, 0): {"type": "USINT", "default": 0xAC}, (0x608C, 0): {"type": "USINT", "default": 0xA4},
    (0x608E, 0): {"type": "USINT", "default": 0xA3},
    (0x1C00, 1): {"default": 1}, (0x1C00, 2): {"default": 2}, (0x1C00, 3): {"default": 3}, (0x1C00, 4): {"default": 4},
    # all four PDOs of each direction assigned by default, as all four are valid on CANopen (decision HDT-7)
    (0x1C12, 0): {"default": 4, "min": 0, "max": 4}, (0x1C13, 0): {"default": 4, "min": 0, "max": 4},
}
HDT_NODE_ID = 1  # decision HDT-4: COB-ID defaults "xxxh+Node-ID" evaluated for node 1 (the screenshots')
HDT_ONLY_NTT = (0x2023, 0x203D, 0x2082, 0x2083, 0x2084)


def build_hdt(ref: Path) -> dict[str, Any]:
    rows = list(csv.DictReader((ref / "hdt" / "objects.csv").open(encoding="utf-8")))
    objects: dict[int, dict[str, Any]] = {}
    for r in rows:
        index = int(r["index"], 16)
        sub = int(r["subindex"])
        obj = objects.get(index)
        if obj is None:
            code = r["object_code"] or ("VAR" if sub == 0 and index not in HDT_NAMES else "RECORD")
            name = HDT_NAMES.get(index, r["name"])
            obj = objects[index] = new_object(index, name, code, r["section"])
            if index in HDT_ONLY_NTT:
                obj["requires"] = "ntt"
        if obj["object_code"] == "VAR" and (sub > 0 or index in HDT_NAMES):
            obj["object_code"] = "RECORD"
        nt = norm_type(r["data_type"])
        if nt is None:
            nt = ("UDINT", 32) if index in (0x1005,) else ("UINT", 16)  # decision HDT-5 (undocumented types)
        typ, bits = nt
        acc = r["access"].strip().lower() or ("ro" if sub == 0 and obj["object_code"] != "VAR" else "rw")
        if acc == "w":
            acc = "wo"
        pm = r["pdo_mapping"].strip().lower()
        mappable = pm.startswith("yes") and not (sub == 0 and obj["object_code"] != "VAR")
        dtext = r["default"].strip()
        m = re.fullmatch(r"([0-9A-Fa-f]+)h\+Node-ID", dtext)
        if m:
            default: Any = int(m.group(1), 16) + HDT_NODE_ID
        elif typ == "STRING":
            default = None
        elif _DECIMAL_COMMA.search(dtext):
            default = None  # decimal-comma display values (decision HDT-6)
        else:
            default = fit_default(typ, bits, parse_default(dtext))
        # the range is read with the decided type (608Ah/608Ch/608Eh hold ACh/A4h/A3h, decision HDT-8)
        rtyp = HDT_FIX.get((index, sub), {}).get("type", typ)
        lo, hi, values = clean_spec(rtyp, bits, parse_range_spec(r["value_range"]))
        if typ == "STRING":
            bits = 0
        e = entry(sub, r["name"], typ, bits, acc, pdo_dirs(mappable, acc), default, lo, hi, r["units"].strip(),
                  f"§{r['section']}", values=values)
        if index in (0x6060,):
            e["enum"] = {"-2": "Press", "-1": "Gearbox / electrical axis", "1": "Profile position", "2": "Velocity (vl)",
                         "3": "Profile velocity", "4": "Torque", "6": "Homing", "7": "Interpolated position",
                         "8": "Cyclic synchronous position", "9": "Cyclic synchronous velocity",
                         "10": "Cyclic synchronous torque"}
        for k, v in HDT_FIX.get((index, sub), {}).items():
            if k == "comment":
                e["comment"] = f"§{r['section']}; {v}"
            else:
                e[k] = v
        if not e.get("pdo"):
            e.pop("pdo", None)
        if (index, sub) == (0x1010, 4):
            continue  # "only in 2.08 table": sub0 = 3 with the three named sub-indices (ambiguity 1)
        obj["entries"][sub] = e
    for idx in (0x1C12, 0x1C13):
        for sub in range(1, 5):
            e = objects[idx]["entries"][sub]
            base = 0x1600 if idx == 0x1C12 else 0x1A00
            e["default"] = base + sub - 1
            e["min"], e["max"] = base, base + 3
    return finish("hdt", "HDT DS-301 protocol CANopen - EtherCAT user guide Rev 4.0", objects, len(rows),
                  {"node_id": HDT_NODE_ID})


# ---------------------------------------------------------------------------------------------------------
# Control Techniques SM-EtherCAT (issue 5)
# ---------------------------------------------------------------------------------------------------------

CT_FIX: dict[tuple[int, int], dict[str, Any]] = {
    (0x1605, 2): {"default": 0x60420010, "comment": "Table 6.9 prints 0x60600008; Table 6.6 and 1C12h say 6042h (decision CT-2)"},
    (0x1018, 1): {"default": 0xF9},
    (0x6041, 0): {"access": "ro", "comment": "printed RW; CiA-402 RO (decision CT-4)"},
    (0x6099, 0): {"type": "USINT"},
    (0x60C1, 1): {"type": "DINT", "comment": "printed Unsigned 32; a signed position set-point (ambiguity A17)"},
    (0x60C0, 0): {"comment": "range printed as the single value 0: only linear (decision CT-10)"},
}
CT_MAPPABLE_EXTRA = {0x6040, 0x6041, 0x6042, 0x6044, 0x6060, 0x6061, 0x6062, 0x6064, 0x2830, 0x2831}
#: objects that are writable profile targets or readable actual values the manual lists as cyclic data;
#: CT's guide never gives a PDO-mapping column (digest §8) — decision CT-5
CT_PROFILE_MAPPABLE = {0x6043, 0x6071, 0x6077, 0x6078, 0x607A, 0x60F4, 0x60B1, 0x60C1, 0x603F}


def build_controltechniques(ref: Path) -> dict[str, Any]:
    rows = list(csv.DictReader((ref / "controltechniques" / "objects.csv").open(encoding="utf-8")))
    objects: dict[int, dict[str, Any]] = {}
    for r in rows:
        if not r["index"].startswith("0x") or "+" in r["index"]:
            continue  # 0x2000+menu pattern rows: drive parameters are built from parameters.csv below
        index = int(r["index"], 16)
        subtext = r["subindex"].strip()
        if not subtext:
            continue  # 605Dh/6065h/6067h: "listed as supported only; no object table" (decision CT-6)
        if index in (0x2012, 0x2014, 0x203D):
            continue  # parameter examples; built with the drive parameters
        m = re.fullmatch(r"(\d+)-(\d+)", subtext)
        subs = range(int(m.group(1)), int(m.group(2)) + 1) if m else range(int(subtext), int(subtext) + 1)
        if m and index in (0x1615, 0x1A15):
            subs = range(int(m.group(1)), 6)  # CF = 5 (decision CT-3)
        if m and index in (0x1C12, 0x1C13):
            subs = range(int(m.group(1)), 3)  # at most two PDOs assigned (decision CT-3)
        oname, _, ename = r["name"].partition(": ")
        if not ename:
            ename = oname
        obj = objects.get(index)
        if obj is None:
            obj = objects[index] = new_object(index, oname, "VAR", r["section"])
        nt = norm_type(r["data_type_or_size"]) or ("UINT", 16)
        typ, bits = nt
        if "type" in CT_FIX.get((index, subs[0]), {}):
            typ = CT_FIX[(index, subs[0])]["type"]
        acc = (r["access"] or "ro").strip().lower()
        pm = r["pdo_mapping"].strip().lower()
        cyclic_only = pm.startswith("cyclic only")
        mappable = (pm.startswith("yes") or cyclic_only or index in CT_PROFILE_MAPPABLE) and not pm.startswith("no")
        default = fit_default(typ, bits, parse_default(r["default"]))
        if r["default"].strip().startswith(("See", "High", "N/A")):
            default = None
        spec = parse_range_spec(r["value_range"])
        if index == 0x6098:
            spec = RangeSpec(0, 35)  # "15, 16, 31, 32 reserved" (Table 7.59): refused by the drive's own check
        listed = re.search(r"defined values ([-\d, ]+)", r["notes"])
        if listed:  # 605Ah "0 to 6", "defined values 0,1,2,5,6 (Table 7.9)": the list is the range
            spec = parse_range_spec(f"{spec.lo}..{spec.hi} (values {listed.group(1).strip(' ,')})")
        lo, hi, values = clean_spec(typ, bits, spec)
        for sub in subs:
            nm = ename if not m else re.sub(r"1st to 255th mapped objects|assigned [RT]xPDO n",
                                                     f"mapped object {sub}" if "PDO mapping" in oname else f"assigned PDO {sub}",
                                                     ename)
            # sub-index 0 counts are never mappable (decision Profiles-1), whatever the object's list says
            count = sub == 0 and (m is not None or "sub-ind" in r["name"].lower())
            e = entry(sub, nm, typ, bits, acc, "" if count else pdo_dirs(mappable, acc), default, lo, hi,
                      "" if r["units"].strip() == "N/A" else r["units"].strip(), f"§{r['section']}", values=values)
            if cyclic_only:
                e["category"] = "pdo-only"
            if 0x1600 <= index <= 0x1BFF and sub > 0:
                e.setdefault("default", 0)
            if index in (0x1C12, 0x1C13) and sub > 1:
                e.setdefault("default", 0)
            fix = CT_FIX.get((index, sub), {})
            for k, v in fix.items():
                if k == "comment":
                    e["comment"] = f"§{r['section']}; {v}"
                elif k != "type":
                    e[k] = v
            if index == 0x6041:
                e["pdo"] = "T"
            if not e.get("pdo"):
                e.pop("pdo", None)
            obj["entries"][sub] = e
        if len(obj["entries"]) > 1 or 0 not in obj["entries"]:
            obj["object_code"] = "RECORD"
    for idx in (0x1600, 0x1601, 0x1605, 0x1615, 0x1A00, 0x1A01, 0x1A02, 0x1A05, 0x1A15):
        o = objects[idx]
        o["entries"][0]["max"] = 5
        for sub in range(1, 6):
            if sub not in o["entries"]:
                o["entries"][sub] = entry(sub, f"mapped object {sub}", "UDINT", 32, "rw", default=0,
                                          comment="§6.3.2/6.3.3; CF = 5 (decision CT-3)")
    for idx in (0x1C12, 0x1C13):
        o = objects[idx]
        o["entries"][0]["max"] = 2
    objects[0x6060]["entries"][0]["enum"] = {"0": "No mode change", "2": "vl velocity", "4": "Profile torque",
                                              "6": "Homing", "7": "Interpolated position",
                                              "8": "Cyclic synchronous position"}
    # named in the support lists without a table (605Dh, 6065h, 6067h): CiA-402 types (decision CT-6)
    for idx, nm, typ, bits in ((0x605D, "halt_option_code", "INT", 16), (0x6065, "following_error_window", "UDINT", 32),
                               (0x6067, "position_window", "UDINT", 32)):
        o = objects[idx] = new_object(idx, nm, "VAR", "7.3.1/7.3.14")
        o["entries"][0] = entry(0, nm, typ, bits, "rw", comment="listed as supported only; type from CiA-402 (decision CT-6)")
    n_params = add_ct_parameters(ref, objects)
    return finish("controltechniques", "Control Techniques SM-EtherCAT User Guide issue 5", objects, len(rows),
                  {"parameter_rows": n_params})


CT_SLOT_MENU = 15  # the SM-EtherCAT module is taken to sit in slot 1 (decision CT-7)
CT_SLOW_MENUS = (70, 71)  # SM-Applications PLC registers, reached through Inter-Option communication (decision CT-8)


def _ct_param_object(objects: dict[int, dict[str, Any]], menu: int, section: str) -> dict[str, Any]:
    index = 0x2000 + menu
    if index not in objects:
        objects[index] = new_object(index, f"Menu {menu} parameters", "ARRAY" if menu >= 60 else "RECORD", section)
    return objects[index]


def add_ct_parameters(ref: Path, objects: dict[int, dict[str, Any]]) -> int:
    """Drive/module parameters as objects 0x2000+menu, sub-index = parameter (§6.2); returns the CSV rows."""
    rows = list(csv.DictReader((ref / "controltechniques" / "parameters.csv").open(encoding="utf-8")))
    for r in rows:
        menu_txt, _, par_txt = r["menu.param"].partition(".")
        par = int(par_txt)
        if par == 0:
            continue  # Pr MM.00 is reached only as Pr 61.01 (0x203D:01), §6.2
        lo, hi = parse_range(r["range"])
        if r["range"].strip().upper().startswith("OFF") or "(OFF)" in r["range"]:
            lo, hi = 0, 1
        dm = re.match(r"\s*(-?\d+)", r["default"])
        default = int(dm.group(1)) if dm else (0 if r["default"].strip().upper().startswith("OFF") else None)
        acc = r["access"].strip().lower() or "rw"
        typ, bits = ("INT", 16) if "16-bit" in r["name"] else ("DINT", 32)  # size of a parameter: decision CT-9
        menus = (CT_SLOT_MENU, 60) if menu_txt == "MM" else (int(menu_txt),)
        for menu in menus:
            obj = _ct_param_object(objects, menu, r["section"])
            obj["entries"][par] = entry(par, f"Pr {menu_txt}.{par:02d} {r['name']}", typ, bits, acc,
                                        pdo_dirs(True, acc), default, *clean_range(typ, bits, lo, hi),
                                        comment=f"§{r['section']}; {r['meaning'][:160]}")
    for menu in CT_SLOW_MENUS:
        obj = _ct_param_object(objects, menu, "6.1.1")
        obj["requires"] = "applications-slot"
        obj["name"] = f"Menu {menu} SM-Applications PLC registers"
        for par in range(1, 100):
            obj["entries"][par] = entry(par, f"Pr {menu}.{par:02d}", "DINT", 32, "rw", "RT", 0, category="slow",
                                        comment="slow parameter: only in the 2nd PDO of an SM (§6.1.1, decision CT-8)")
    for o in objects.values():
        if 0x2000 <= o["index"] <= 0x2063:
            top = max(o["entries"])
            o["entries"][0] = entry(0, "Highest parameter number", "USINT", 8, "ro", default=top,
                                    comment="§6.2: sub-index 0 of a menu returns its highest parameter number")
    return len(rows)


def main(argv: list[str]) -> int:
    ref = Path(argv[1]) if len(argv) > 1 else ROOT.parent / "shared" / "reference"
    DATA.mkdir(parents=True, exist_ok=True)
    for name, fn in (("technosoft", build_technosoft), ("hdt", build_hdt), ("controltechniques", build_controltechniques)):
        data = fn(ref)
        path = DATA / f"{name}.json"
        path.write_text(json.dumps(data, indent=1, ensure_ascii=False) + "\n", encoding="utf-8")
        print(f"{path}: {len(data['objects'])} objects from {data['csv_rows']} CSV rows")
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv))
