"""Explain factor-group values read from a drive or a file: what one user unit is in counts, what the
velocity and acceleration units mean, and whether the objects agree with each other."""

from __future__ import annotations

from dataclasses import dataclass, field
from fractions import Fraction
from typing import TYPE_CHECKING, Any

from ecattool.errors import InputError, Location, TargetError
from ecattool.findings import Finding, Severity
from ecattool.od.numbers import parse_address, parse_int
from ecattool.od.types import lookup
from ecattool.scaling.compute import (
    FAMILIES,
    _types,
    fixed_counts_per_rev,
    resolve_family,
    technosoft_factor_set,
)
from ecattool.scaling.model import MAX_COUNTS, MAX_SLOW_LOOP, MIN_SLOW_LOOP
from ecattool.scaling.units import decode_si_unit, describe_dimension
from ecattool.startup import import_file

if TYPE_CHECKING:
    from ecattool.esi.model import Device
    from ecattool.scaling.group import FactorGroup

Values = dict[tuple[int, int], int]

#: the factor-group objects a project's startup list sets (6089h–60ABh): what ``scale explain --project`` reads
FACTOR_INDICES = range(0x6089, 0x60AC)


def explain_family(family: str | None) -> str:
    """The family :func:`explain` reads a drive of ``family`` (a project slave's) as: the scaling family of that
    name, else the generic CiA-402 one."""
    return family if family in FAMILIES else "generic"


def family_drives(family: str, firmware: str | None = None) -> list[Device]:
    """What a bare simulator holds to explain ``family``'s values on (``scale explain --target sim``), and whose
    timeouts a real bus takes: the built-in family's drive (at ``firmware`` where given); none for ``generic``."""
    from ecattool import profiles

    if family not in profiles.PROFILE_NAMES:
        return []
    return [profiles.load(family, revision=firmware) if firmware else profiles.load(family)]


@dataclass(slots=True)
class Explanation:
    family: str
    factor_set: str
    lines: list[tuple[str, str]] = field(default_factory=list)
    data: dict[str, Fraction | str] = field(default_factory=dict)
    findings: list[Finding] = field(default_factory=list)

    def to_json(self) -> dict[str, Any]:
        def conv(v: Any) -> Any:
            if isinstance(v, Fraction):
                return {"exact": f"{v.numerator}/{v.denominator}" if v.denominator != 1 else v.numerator, "value": float(v)}
            return v

        return {"family": self.family, "factor_set": self.factor_set,
                "lines": [{"quantity": q, "meaning": m} for q, m in self.lines],
                "data": {k: conv(v) for k, v in self.data.items()},
                "findings": [f.to_json() for f in self.findings]}


def _g(x: Fraction) -> str:
    if x.denominator == 1:
        return str(x.numerator)
    return f"{float(x):.10g} ({x.numerator}/{x.denominator})" if max(x.numerator, x.denominator) < 10**7 else f"{float(x):.10g}"


class _Reader:
    def __init__(self, values: Values, location: Location | None) -> None:
        self.v = values
        self.loc = location

    def has(self, index: int) -> bool:
        return (index, 1) in self.v or (index, 2) in self.v

    def ratio(self, index: int, default: Fraction | None = None) -> Fraction | None:
        if not self.has(index):
            return default
        num, den = self.v.get((index, 1), 1), self.v.get((index, 2), 1)
        if den == 0:
            raise InputError(f"0x{index:04X}:02 is 0: a divisor cannot be zero", self.loc)
        if num == 0:
            raise InputError(f"0x{index:04X}:01 is 0: the factor would erase every value", self.loc)
        return Fraction(num, den)


def _consistency(e: Explanation, what: str, stored: Fraction | None, expected: Fraction | None, loc: Location | None) -> None:
    if stored is None or expected is None or expected == 0 or stored == 1:
        return  # 1/1 is the drive's default: internal units, the informative objects are not in use
    ppm = (stored - expected) / expected * 1_000_000
    e.data[f"{what} mismatch [ppm]"] = ppm
    if abs(ppm) > 1:
        e.findings.append(Finding("scaling.inconsistent", Severity.WARNING,
                                  f"{what}: stored {float(stored):.10g} but the other objects give {float(expected):.10g} "
                                  f"({float(ppm):+.3g} ppm)", loc))


#: CiA 402's types of the objects explain reads, where the family's dictionary does not have them
_STANDARD_TYPES = {0x604B: "INTEGER16", 0x604C: "INTEGER32", 0x607E: "UNSIGNED8", 0x6089: "INTEGER8",
                   0x608A: "UNSIGNED8", 0x608B: "INTEGER8", 0x608C: "UNSIGNED8", 0x608D: "INTEGER8",
                   0x608E: "UNSIGNED8", 0x206F: "INTEGER8", 0x2070: "UNSIGNED16"}


def _check_types(values: Values, family: str, firmware: str | None, location: Location | None) -> None:
    """Every value fits the data type of the object it is given for (the family's dictionary, else CiA 402's;
    UNSIGNED32 for the factor pairs): 6093:01 = 2^32 or -1 is refused, never wrapped or taken as a ratio."""
    od = _types(None, family, firmware)
    for (index, sub), value in values.items():
        if isinstance(value, bool) or not isinstance(value, int):
            raise InputError(f"0x{index:04X}:{sub:02X} = {value!r} is not an integer", location)
        entry = od.entry(index, sub) if od is not None else None
        dt = entry.datatype if entry is not None else None
        if dt is None:
            name = _STANDARD_TYPES.get(index, "UNSIGNED32")
            dt = lookup(name)
        bounds = dt.range() if dt is not None else None
        if dt is not None and bounds is not None and not bounds[0] <= value <= bounds[1]:
            raise InputError(f"0x{index:04X}:{sub:02X} = {value} does not fit its type {dt.name} "
                             f"({bounds[0]}..{bounds[1]})", location)


def explain(values: Values, family: str = "technosoft-ipos", *, slow_loop: Fraction = Fraction(1, 1000),
            counts_per_rev: Fraction | int | None = None, firmware: str | None = None,
            factor_set: str | None = None, location: Location | None = None) -> Explanation:
    """What the factor objects in ``values`` ({(index, sub): value}) mean for ``family``.

    ``counts_per_rev`` (increments per motor revolution) lets velocities be told in rpm where the objects
    do not carry it (608Fh does on CiA-402-2 drives; HDT is always 65536).
    """
    fam = resolve_family(family, location)
    _check_types(values, fam, firmware, location)

    if not MIN_SLOW_LOOP <= Fraction(slow_loop) <= MAX_SLOW_LOOP:
        raise InputError(f"slow-loop period {Fraction(slow_loop)} s is out of range ({MIN_SLOW_LOOP} .. {MAX_SLOW_LOOP} s)",
                         location)
    if counts_per_rev is not None and not 1 <= Fraction(counts_per_rev) <= MAX_COUNTS:
        raise InputError(f"counts per revolution {counts_per_rev} is out of range (1 .. {MAX_COUNTS})", location)
    if fam == "technosoft-ipos":
        fs = factor_set or (technosoft_factor_set(firmware) if firmware else (
            "obsolete" if (0x2071, 1) in values or (0x608A, 0) in values and (0x210F, 1) not in values else "cia402-2"))
    else:
        fs = fam
    e = Explanation(fam, fs)
    r = _Reader(values, location)
    T = Fraction(slow_loop)
    cpr: Fraction | None = Fraction(counts_per_rev) if counts_per_rev else None
    fixed = fixed_counts_per_rev(fam)
    if fixed is not None:
        cpr = Fraction(fixed)
    elif r.has(0x608F):
        cpr = r.ratio(0x608F)

    def rev(counts: Fraction, per: str) -> str:
        return f" = {_g(counts / cpr)} motor rev{per}" if cpr else ""

    def rpm(counts_per_s: Fraction, per: str = "") -> str:
        return f" = {_g(counts_per_s * 60 / cpr)} motor rpm{per}" if cpr else ""

    pf: Fraction | None = None
    if fs in ("cia402-2", "obsolete", "hdt") and r.has(0x6093):
        pf = r.ratio(0x6093)
    elif r.has(0x6092) or r.has(0x6091) or r.has(0x608F):
        res, gear, feed = r.ratio(0x608F, Fraction(1)), r.ratio(0x6091, Fraction(1)), r.ratio(0x6092, Fraction(1))
        assert res is not None and gear is not None and feed is not None
        pf = res * gear / feed
    if fs == "cia402-2" and pf is not None and r.has(0x6092):
        res, gear, feed = r.ratio(0x608F, Fraction(1)), r.ratio(0x6091, Fraction(1)), r.ratio(0x6092, Fraction(1))
        assert res is not None and gear is not None and feed is not None
        _consistency(e, "6093h vs 608Fh x 6091h / 6092h", pf, res * gear / feed, location)
    unit_name = {0: "position unit", 1: "velocity unit", 2: "acceleration unit", 3: "jerk unit"}
    for i, index in enumerate((0x60A8, 0x60A9, 0x60AA, 0x60AB)):
        if values.get((index, 0)):
            unit_name[i] = decode_si_unit(values[(index, 0)])
            e.data[f"0x{index:04X}"] = unit_name[i]
    if pf is not None:
        e.data["counts per position unit"] = pf
        e.lines.append(("position", f"1 {unit_name[0]} = {_g(pf)} counts{rev(pf, '')}"))
        e.lines.append(("position", f"1 count = {_g(1 / pf)} {unit_name[0]}"))

    if fs in ("cia402-2", "obsolete"):
        tech = _technosoft(e, r, T, unit_name, fs, location)
        for what, cps in tech.items():
            per = {"velocity": "", "acceleration": "/s", "jerk": "/s²"}[what]
            e.lines.append((what, f"1 {unit_name[{'velocity': 1, 'acceleration': 2, 'jerk': 3}[what]]} = "
                                  f"{_g(cps)} counts/s{'' if what == 'velocity' else '²' if what == 'acceleration' else '³'}"
                                  f"{rpm(cps, per)}"))
    elif fs == "hdt":
        for index, what, per in ((0x6094, "velocity", ""), (0x6097, "acceleration", "/s")):
            pulses = r.ratio(index)
            if pulses is not None:
                e.data[f"counts/s{'' if not per else '²'} per {what} unit"] = pulses
                e.lines.append((what, f"1 {unit_name[1 if what == 'velocity' else 2]} = {_g(pulses)} pulses/s"
                                      f"{'²' if per else ''}{rpm(pulses, per)}"))
        acc = r.ratio(0x6097)
        if acc is not None:
            e.lines.append(("jerk", f"2011h: 1 unit = {_g(acc)} pulses/s³ (acceleration unit per second)"))
    elif fs == "generic" and pf is not None:
        vf, af, jf = r.ratio(0x6096), r.ratio(0x6097), r.ratio(0x60A2)
        if vf is not None:
            cps = pf / vf
            e.data["counts/s per velocity unit"] = cps
            e.lines.append(("velocity", f"1 {unit_name[1]} = {_g(cps)} counts/s{rpm(cps)}"))
            if af is not None:
                cps2 = cps / af
                e.data["counts/s² per acceleration unit"] = cps2
                e.lines.append(("acceleration", f"1 {unit_name[2]} = {_g(cps2)} counts/s²{rpm(cps2, '/s')}"))
                if jf is not None:
                    e.lines.append(("jerk", f"1 {unit_name[3]} = {_g(cps2 / jf)} counts/s³"))
    if fam in ("controltechniques", "hdt") and (r.has(0x604C) or r.has(0x604B)):
        dim, sp = r.ratio(0x604C, Fraction(1)), r.ratio(0x604B, Fraction(1))
        assert dim is not None and sp is not None
        e.data["rpm per 6042h unit"] = dim * sp
        e.lines.append(("vl velocity", f"6042h: 1 unit = {_g(dim * sp)} rpm (604B x 604C, multiplicative reading)"))
    if fam == "technosoft-ipos":
        used = (0x6093, 0x6094, 0x6097, 0x2071) if fs == "obsolete" else (0x6093, 0x6094, 0x210F, 0x2110)
        for index in used:
            num, den = values.get((index, 1)), values.get((index, 2), 1)
            if num is not None and num != den and max(num, den) < 0x10000:
                e.findings.append(Finding("scaling.small-pair", Severity.WARNING,
                                          f"0x{index:04X} = {values[(index, 1)]}/{values.get((index, 2), 1)}: Technosoft "
                                          "computes small pairs with round-off (§5.1.10.1); write e.g. "
                                          f"{values[(index, 1)] << 16}/{values.get((index, 2), 1) << 16}", location))
    if ((0x607E, 0) in values):
        pol = values[(0x607E, 0)]
        e.lines.append(("polarity", f"607Eh = 0x{pol:02X}: positions {'inverted' if pol & 0x80 else 'normal'}, "
                                    f"velocities {'inverted' if pol & 0x40 else 'normal'}"))
    if not e.lines:
        raise InputError("no scaling objects to explain (give e.g. 6093:01=… 6093:02=…)", location)
    return e


def _technosoft(e: Explanation, r: _Reader, T: Fraction, unit_name: dict[int, str], fs: str,
                loc: Location | None) -> dict[str, Fraction]:
    """Technosoft: velocity IU = 1/65536 count per slow loop T, acceleration IU per T², jerk per T³."""
    out: dict[str, Fraction] = {}
    idx = {"velocity": 0x6094, "acceleration": 0x210F if fs == "cia402-2" else 0x6097, "jerk": 0x2110}
    for order, (what, index) in enumerate(idx.items(), start=1):
        if fs == "obsolete" and what == "jerk":
            continue
        iu = r.ratio(index)
        if iu is None:
            continue
        out[what] = iu / 65536 / T**order
        e.data[f"IU per {what} unit"] = iu
        e.data[f"counts/s{('', '²', '³')[order - 1]} per {what} unit"] = out[what]
    if fs == "cia402-2":
        pf, vf, af, jf = r.ratio(0x6093), r.ratio(0x6096), r.ratio(0x6097), r.ratio(0x60A2)
        v, a, j = r.ratio(0x6094), r.ratio(0x210F), r.ratio(0x2110)
        if pf and vf:
            _consistency(e, "6094h vs 6093h / 6096h x T x 2^16", v, pf / vf * T * 65536, loc)
        if v and af:
            _consistency(e, "210Fh vs 6094h / 6097h x T", a, v / af * T, loc)
        if a and jf:
            _consistency(e, "2110h vs 210Fh / 60A2h x T", j, a / jf * T, loc)
    else:
        tf = r.ratio(0x2071)
        if tf is not None:
            e.data["slow-loop samples per time unit"] = tf
            e.lines.append(("time", f"1 time unit = {_g(tf)} slow-loop samples = {_g(tf * T * 1000)} ms"))
        for label, dim_i, not_i, factor in (("position", 0x608A, 0x6089, 0x6093), ("velocity", 0x608C, 0x608B, 0x6094),
                                            ("acceleration", 0x608E, 0x608D, 0x6097), ("time", 0x2070, 0x206F, 0x2071)):
            if (dim_i, 0) in r.v or (not_i, 0) in r.v:
                dim, notation = r.v.get((dim_i, 0), 0), r.v.get((not_i, 0), 0)
                notation = notation - 256 if notation > 127 else notation
                active = dim != 0 or notation != 0
                e.lines.append((label, f"dimension {dim}, notation {notation}: {describe_dimension(dim, notation)}; "
                                       f"0x{factor:04X} {'active' if active else 'INACTIVE (indices 0)'}"))
    return out


def explain_group(group: FactorGroup) -> Explanation:
    """A computed factor group read back as :func:`explain` reads a drive's values (its own factor set, which
    only a Technosoft family has more than one of): the page ``scale compute --html`` draws."""
    return explain(group.values, group.family, factor_set=group.factor_set)


#: every object explain() understands (index, sub-indices)
SCALING_OBJECTS: tuple[tuple[int, tuple[int, ...]], ...] = (
    (0x608F, (1, 2)), (0x6091, (1, 2)), (0x6092, (1, 2)), (0x6093, (1, 2)), (0x6094, (1, 2)), (0x6096, (1, 2)),
    (0x6097, (1, 2)), (0x210F, (1, 2)), (0x60A2, (1, 2)), (0x2110, (1, 2)), (0x2071, (1, 2)), (0x604B, (1, 2)),
    (0x604C, (1, 2)), (0x60A8, (0,)), (0x60A9, (0,)), (0x60AA, (0,)), (0x60AB, (0,)), (0x607E, (0,)),
    (0x6089, (0,)), (0x608A, (0,)), (0x608B, (0,)), (0x608C, (0,)), (0x608D, (0,)), (0x608E, (0,)),
    (0x206F, (0,)), (0x2070, (0,)),
)
_SIGNED = {0x604B, 0x604C, 0x6089, 0x608B, 0x608D, 0x206F}  # INT/DINT vl factors, INTEGER8 notation indices


def read_values(slave: Any) -> Values:
    """Read the scaling objects a drive has over SDO (any :class:`~ecattool.target.base.SlaveTarget`).

    Objects the drive aborts on (absent, not readable) are skipped; the result feeds :func:`explain`.
    """
    values: Values = {}
    for index, subs in SCALING_OBJECTS:
        for sub in subs:
            try:
                data = slave.sdo_upload(index, sub, size=4)  # every factor and SI unit object is 32 bits at most
            except TargetError:
                break
            values[(index, sub)] = int.from_bytes(data, "little", signed=index in _SIGNED)
    return values


def values_from_file(path: str) -> Values:
    """Values from a startup file of any format, an ecattool `scale compute --json` file, or a YAML/JSON mapping."""
    import json

    from ecattool.fileio import read_bytes

    raw = read_bytes(path)
    try:
        doc = json.loads(raw)
    except (ValueError, UnicodeDecodeError, RecursionError):  # RecursionError: [[[[… nested 100000 deep
        doc = None
    if isinstance(doc, dict) and "objects" in doc and "factor_set" in doc:
        objects = doc["objects"]
        found: dict[tuple[int, int], int] = {}
        for i, o in enumerate(objects if isinstance(objects, list) else [objects]):
            if not isinstance(o, dict) or not {"index", "subindex", "value"} <= set(o):
                raise InputError(f"objects[{i}] of a `scale compute --json` file needs index, subindex and value",
                                 Location(path))
            try:
                found[(parse_int(o["index"]), parse_int(o["subindex"]))] = parse_int(o["value"])
            except InputError as exc:
                raise InputError(f"objects[{i}]: {exc.message}", Location(path)) from None
        return found
    if doc is None and raw.lstrip()[:1] not in (b"<",):
        from ecattool.yamlloc import load_yaml

        try:
            y = load_yaml(raw, path)  # bytes: load_yaml decodes (BOM, invalid UTF-8 as an InputError)
            doc = y.data
        except InputError:
            doc = None
    if isinstance(doc, dict) and doc and all(":" in str(k) for k in doc):
        return {parse_address(str(k), Location(path)): parse_int(v if isinstance(v, (int, str)) else str(v), Location(path))
                for k, v in doc.items()}

    values: dict[tuple[int, int], int] = {}
    for cfg in import_file(path):
        for c in cfg.commands:
            values[(c.index, c.subindex)] = c.int_value
    if not values:
        raise InputError("no object values found", Location(path))
    return values
