"""The PDO mapping model and its parsers (compact text, whole-mapping CLI syntax, dict/YAML data).

A :class:`Mapping` holds, per direction, the PDOs assigned to the process-data sync manager (SM2 for RX,
SM3 for TX) in assignment order; each :class:`MappedPdo` holds its entries as
:class:`ecattool.esi.model.PdoEntry` (index, sub-index, bit length; gaps have index 0). Every PDO and entry
remembers where it was written (:class:`ecattool.errors.Location`), so findings point at the file and line.

Entry syntax (one entry)::

    0x6040:00/16     6040:0/16     #x6040:00/16   address with bit length
    0x6040:00        6040          address; the length is taken from the device dictionary
    controlword      statusword/16 object name (ObjectDictionary.find), optional length
    0x60400010                     a raw 32-bit mapping value (index<<16 | sub<<8 | bits)
    gap/8            0/8           a gap (padding) of 8 bits, written as index 0

Whole-mapping syntax (one direction, as on the command line)::

    0x1600=controlword,0x607A:00/32;0x1601=0x60FE:01/32   PDOs separated by ';', entries by ','
    0x1600;0x1601                                         assign PDOs and keep their device contents
    controlword,0x607A:00/32                              entries only: the direction's first PDO
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Mapping as AbcMapping
from dataclasses import dataclass, field
from typing import Any

from ecattool.errors import InputError, Location
from ecattool.esi.model import Device, Direction, Pdo, PdoEntry
from ecattool.od.numbers import parse_int
from ecattool.od.standard import standard_bits

#: where mapping objects live (CiA-301): RxPDO mapping 0x1600-0x17FF, TxPDO mapping 0x1A00-0x1BFF
RX_RANGE = range(0x1600, 0x1800)
TX_RANGE = range(0x1A00, 0x1C00)

_GAP_WORDS = ("gap", "pad", "padding", "dummy")
_ENTRY_RE = re.compile(
    r"^(?:0x|#x)?(?P<index>[0-9a-f]{1,4})h?\s*(?::\s*(?:0x|#x)?(?P<sub>[0-9a-f]{1,2})h?)?\s*(?:/\s*(?P<bits>\d+))?$",
    re.IGNORECASE,
)
_RAW_RE = re.compile(r"^(?:0x|#x)(?P<value>[0-9a-f]{8})$", re.IGNORECASE)


def pdo_index(text: str | int, location: Location | None = None) -> int:
    """A PDO (mapping object) index: ``0x1600``, ``#x1A00``, ``1600h``, 5632; must fit 16 bits."""
    index = parse_int(text, location, "PDO index")
    if not 0 < index <= 0xFFFF:
        raise InputError(f"{text!r} is not a PDO index (RxPDOs 0x1600-0x17FF, TxPDOs 0x1A00-0x1BFF)", location)
    return index


def pdo_direction(index: int) -> Direction | None:
    """The direction a mapping object index belongs to by its number (None outside both ranges)."""
    if index in RX_RANGE:
        return Direction.RX
    if index in TX_RANGE:
        return Direction.TX
    return None


@dataclass(slots=True)
class MappedPdo:
    """One PDO assigned to a sync manager: its mapping object index and entries.

    ``explicit`` is False when the entries were not given and come from the device (the PDO keeps its
    default or fixed contents and is not rewritten by :func:`ecattool.pdo.program`).
    """

    index: int
    entries: list[PdoEntry] = field(default_factory=list)
    explicit: bool = True
    name: str = ""
    location: Location | None = None

    @property
    def bit_size(self) -> int:
        return sum(e.bit_len for e in self.entries)

    def to_json(self) -> dict[str, Any]:
        return {
            "index": f"0x{self.index:04X}",
            "explicit": self.explicit,
            "entries": [entry_text(e) for e in self.entries],
        }


@dataclass(slots=True)
class Mapping:
    """PDO assignment and mapping per direction.

    ``given`` holds the directions the user specified; the others carry the device default and are left
    alone when programming.
    """

    rx: list[MappedPdo] = field(default_factory=list)
    tx: list[MappedPdo] = field(default_factory=list)
    given: set[Direction] = field(default_factory=set)
    source: str = ""

    def pdos(self, direction: Direction) -> list[MappedPdo]:
        return self.rx if direction is Direction.RX else self.tx

    def set_pdos(self, direction: Direction, pdos: list[MappedPdo]) -> None:
        if direction is Direction.RX:
            self.rx = pdos
        else:
            self.tx = pdos

    def bit_size(self, direction: Direction) -> int:
        return sum(p.bit_size for p in self.pdos(direction))

    def to_json(self) -> dict[str, Any]:
        return {d.value: [p.to_json() for p in self.pdos(d)] for d in Direction}

    def to_data(self) -> dict[str, Any]:
        """The dict/YAML form :meth:`from_data` reads (given directions only; PDOs kept as they are have no
        ``entries``)."""
        return {
            d.value: [{"index": f"0x{p.index:04X}", **({"entries": [entry_text(e) for e in p.entries]}
                                                       if p.explicit else {})} for p in self.pdos(d)]
            for d in Direction if d in self.given
        }

    def to_text(self, direction: Direction) -> str:
        """The whole-mapping syntax of one direction (what ``--rx``/``--tx`` take)."""
        return ";".join(
            f"0x{p.index:04X}=" + ",".join(entry_text(e) for e in p.entries) if p.explicit else f"0x{p.index:04X}"
            for p in self.pdos(direction)
        )

    # --- constructors ----------------------------------------------------------------------------
    @classmethod
    def from_text(
        cls,
        rx: str | Iterable[str] | None = None,
        tx: str | Iterable[str] | None = None,
        device: Device | None = None,
        default: "Mapping | None" = None,
        source: str = "<command line>",
    ) -> "Mapping":
        """Build a mapping from the whole-mapping syntax (``--rx``/``--tx`` on the command line).

        Directions left as None keep ``default`` (or the device default when a device is given).
        """
        base = default if default is not None else (default_mapping(device) if device is not None else Mapping())
        out = Mapping(rx=list(base.rx), tx=list(base.tx), source=source)
        for direction, spec in ((Direction.RX, rx), (Direction.TX, tx)):
            if spec is None:
                continue
            specs = [spec] if isinstance(spec, str) else list(spec)
            if not specs:
                continue
            pdos: list[MappedPdo] = []
            for n, one in enumerate(specs):
                loc = Location(source, None, None) if len(specs) == 1 else Location(f"{source} --{direction.value} #{n + 1}")
                pdos.extend(parse_direction(one, direction, device, base, loc, taken=[p.index for p in pdos]))
            out.set_pdos(direction, pdos)
            out.given.add(direction)
        return out

    @classmethod
    def from_file(cls, path: str, device: Device | None = None) -> "Mapping":
        """The mapping of a YAML file (``-``: stdin) with ``rx:``/``tx:`` PDO lists, at its top or under a
        ``pdo:`` section (a project drive's), every error located in the file. A file without either list is an
        error: it would silently leave the device's default mapping."""
        from ecattool.fileio import read_input
        from ecattool.yamlloc import load_yaml

        source = "<stdin>" if path == "-" else path
        doc = load_yaml(read_input(path), source)
        data = doc.data
        prefix: tuple[str, ...] = ()
        if isinstance(data, AbcMapping) and "pdo" in data and "rx" not in data and "tx" not in data:
            data, prefix = data["pdo"], ("pdo",)
        if not isinstance(data, AbcMapping) or not {"rx", "tx"} & set(data):
            raise InputError("a mapping file needs rx: and/or tx: PDO lists (or a 'pdo:' section holding them)",
                             doc.locations.get(prefix, Location(source, 1)))
        locations = {where[len(prefix):]: loc for where, loc in doc.locations.items() if where[:len(prefix)] == prefix}
        return cls.from_data(data, device=device, locations=locations, source=source)

    @classmethod
    def from_data(
        cls,
        data: AbcMapping[str, Any] | None,
        device: Device | None = None,
        locations: AbcMapping[tuple[str | int, ...], Location] | None = None,
        default: "Mapping | None" = None,
        source: str = "",
    ) -> "Mapping":
        """Build a mapping from dict/YAML data::

            {"rx": [{"index": "0x1600", "entries": ["controlword", "0x607A:00/32"]}, {"index": 0x1601}],
             "tx": [...]}

        ``locations`` maps value paths *inside data* to locations, e.g. ``("rx", 0, "entries", 1)`` or
        ``("rx", 0)``; the closest located parent is used. A PDO without ``entries`` keeps the device's
        contents. A missing direction keeps ``default`` (or the device default). Other keys (such as
        ``complete_access``) are ignored here.
        """
        locs = dict(locations or {})

        def where(*path: str | int) -> Location | None:
            p = tuple(path)
            while True:
                if p in locs:
                    return locs[p]
                if not p:
                    return Location(source) if source else None
                p = p[:-1]

        if data is None:
            data = {}
        if not isinstance(data, AbcMapping):
            raise InputError("a PDO mapping must be a mapping with 'rx' and/or 'tx' lists", where())
        unknown = [k for k in data if k not in ("rx", "tx", "complete_access", "order")]
        if unknown:
            raise InputError(f"unknown key {unknown[0]!r} in PDO mapping (use rx, tx, complete_access)",
                             where(unknown[0]))
        base = default if default is not None else (default_mapping(device) if device is not None else Mapping())
        out = Mapping(rx=list(base.rx), tx=list(base.tx), source=source)
        for direction in Direction:
            items = data.get(direction.value)
            if items is None:
                continue
            if not isinstance(items, list):
                raise InputError(f"'{direction.value}' must be a list of PDOs", where(direction.value))
            pdos: list[MappedPdo] = []
            for i, item in enumerate(items):
                loc = where(direction.value, i)
                if isinstance(item, (str, int)) and not isinstance(item, bool):
                    item = {"index": item}
                if not isinstance(item, AbcMapping) or "index" not in item:
                    raise InputError("each PDO needs an 'index' (e.g. index: 0x1600)", loc)
                extra = [k for k in item if k not in ("index", "entries", "name")]
                if extra:
                    raise InputError(f"unknown key {extra[0]!r} in a PDO (use index, entries)",
                                     where(direction.value, i, extra[0]))
                index = pdo_index(item["index"], where(direction.value, i, "index"))
                raw_entries = item.get("entries")
                if raw_entries is None:
                    pdos.append(_device_pdo(index, direction, device, base, where(direction.value, i, "index")))
                    continue
                if not isinstance(raw_entries, list):
                    raise InputError("'entries' must be a list", where(direction.value, i, "entries"))
                entries = [
                    parse_entry(e, device, where(direction.value, i, "entries", k))
                    for k, e in enumerate(raw_entries)
                ]
                pdos.append(MappedPdo(index, entries, True, str(item.get("name", "")),
                                      where(direction.value, i, "index")))
            out.set_pdos(direction, pdos)
            out.given.add(direction)
        return out


# --- parsing ---------------------------------------------------------------------------------------


def entry_keys(entries: Iterable[PdoEntry]) -> list[tuple[int, int, int]]:
    """(index, sub-index, bits) of each entry: what a drive compares, names and locations aside."""
    return [(e.index, e.subindex, e.bit_len) for e in entries]


def entry_text(e: PdoEntry) -> str:
    """The compact text of an entry: ``0x6040:00/16``, gaps as ``gap/8``."""
    if e.is_gap:
        return f"gap/{e.bit_len}"
    return f"0x{e.index:04X}:{e.subindex:02X}/{e.bit_len}"


def _from_dictionary(device: Device | None, index: int, sub: int) -> tuple[int | None, str, str]:
    """(bit size, name, type name) of an object entry from the device dictionary or its PDO lists."""
    if device is None:
        return None, "", ""
    entry = device.dictionary.entry(index, sub)
    if entry is not None:
        obj = device.dictionary.get(index)
        name = entry.name
        if obj is not None and obj.name and len(obj.entries) > 1:
            name = f"{obj.name}/{entry.name}" if entry.name else obj.name
        elif obj is not None and obj.name:
            name = obj.name
        return entry.bit_size, name, entry.type_name
    for pdo in (*device.rx_pdos, *device.tx_pdos):
        for pe in pdo.entries:
            if pe.index == index and pe.subindex == sub:
                return pe.bit_len, pe.name, pe.data_type
    return None, "", ""


def _unknown_length(index: int, sub: int, device: Device | None, text: str) -> str:
    """Why ``text`` has no bit length, and the length to write: the CiA-402 one for a standard object."""
    example = f"0x{index:04X}:{sub:02X}/{standard_bits(index, sub) or 16}"
    if device is not None and device.dictionary.entry(index, sub) is None:
        what = "object" if index not in device.dictionary else "sub-index"
        return (f"{text!r}: no such {what} in the dictionary of {device.type_name or 'the device'}, so its bit length "
                f"is unknown; write it as {example} to check the mapping")
    return f"{text!r}: the bit length is unknown, write it as {example}"


def parse_entry(text: str | int, device: Device | None = None, location: Location | None = None) -> PdoEntry:
    """Parse one entry (see the module docstring). Unknown objects parse (the checker reports them);
    a name that the device dictionary does not know, or an address without length for an unknown object,
    raises :class:`InputError`."""
    if isinstance(text, bool):
        raise InputError(f"{text!r} is not a PDO entry", location)
    if isinstance(text, int):
        if not 0 <= text <= 0xFFFFFFFF:
            raise InputError(f"{text} is not a PDO entry (a 32-bit mapping value or an object index)", location)
        if text > 0xFFFF:
            return _complete(PdoEntry.from_mapping_value(text), device, location)
        return _with_bits(text, 0, None, device, location, str(text))
    s = str(text).strip()
    if not s:
        raise InputError("empty PDO entry (write 0x6040:00/16, controlword or gap/8)", location)
    raw = _RAW_RE.match(s)
    if raw:
        return _complete(PdoEntry.from_mapping_value(int(raw.group("value"), 16)), device, location)
    head, slash, bits_text = s.rpartition("/") if "/" in s else (s, "", "")
    bits: int | None = None
    if slash:
        if not bits_text.strip().isdigit():
            # "object/entry" names contain '/' too: treat the whole text as a name then
            head, bits = s, None
        else:
            if len(bits_text.strip()) > 6:  # thousands of digits: no int() of them (Python refuses > 4300)
                raise InputError(f"bit length {bits_text.strip()[:8]}… ({len(bits_text.strip())} digits) in "
                                 f"{head.strip()[:40]!r} is outside 1..255", location)
            bits = int(bits_text)
            if not 1 <= bits <= 255:
                raise InputError(f"bit length {bits} in {s!r} is outside 1..255", location)
    head = head.strip()
    if head.lower() in _GAP_WORDS or head in ("0", "0x0", "0x0000", "0:0", "0x0000:00", "0000:00"):
        if bits is None:
            raise InputError(f"a gap needs a length: write {head}/8", location)
        return PdoEntry(0, 0, bits, "gap", "", location)
    m = _ENTRY_RE.match(head)
    if m and (m.group("sub") is not None or head.lower().startswith(("0x", "#x")) or head.isdigit()
              or head.lower().endswith("h")):
        index = int(m.group("index"), 16)
        sub = int(m.group("sub"), 16) if m.group("sub") is not None else 0
        return _with_bits(index, sub, bits, device, location, s)
    if device is None:
        raise InputError(f"{s!r} is not an entry (write 0x6040:00/16); names need a device", location)
    found = device.dictionary.find(head)
    if found is None:
        raise InputError(f"no object named {head!r} in {device.type_name or 'the device'} "
                         "(write an address like 0x6040:00/16)", location)
    return _with_bits(found[0], found[1], bits, device, location, s)


def _with_bits(index: int, sub: int, bits: int | None, device: Device | None, location: Location | None,
               text: str) -> PdoEntry:
    size, name, type_name = _from_dictionary(device, index, sub)
    if bits is None:
        if size is None or size == 0:
            raise InputError(_unknown_length(index, sub, device, text), location)
        bits = size
    if bits > 255:
        raise InputError(f"{text!r}: {bits} bits do not fit a mapping entry (at most 255)", location)
    return PdoEntry(index, sub, bits, name, type_name, location)


def _complete(e: PdoEntry, device: Device | None, location: Location | None) -> PdoEntry:
    if e.is_gap:
        return PdoEntry(0, 0, e.bit_len, "gap", "", location)
    _, name, type_name = _from_dictionary(device, e.index, e.subindex)
    return PdoEntry(e.index, e.subindex, e.bit_len, name, type_name, location)


def _device_pdo(index: int, direction: Direction, device: Device | None, base: Mapping | None,
                location: Location | None) -> MappedPdo:
    """A PDO assigned by index only: its contents come from the base mapping or the device."""
    if base is not None:
        for p in (*base.rx, *base.tx):
            if p.index == index:
                return MappedPdo(index, [_relocated(e, location) for e in p.entries], False, p.name, location)
    pdo = device.pdo(index) if device is not None else None
    if pdo is not None:
        return MappedPdo(index, [_relocated(e, location) for e in pdo.entries], False, pdo.name, location)
    if device is not None:
        current = _mapping_from_dictionary(device, index)
        if current is not None:
            return MappedPdo(index, [_relocated(e, location) for e in current], False, "", location)
    return MappedPdo(index, [], False, "", location)


def _relocated(e: PdoEntry, location: Location | None) -> PdoEntry:
    return PdoEntry(e.index, e.subindex, e.bit_len, e.name, e.data_type, location or e.location)


def parse_direction(
    text: str,
    direction: Direction,
    device: Device | None = None,
    base: Mapping | None = None,
    location: Location | None = None,
    taken: list[int] | None = None,
) -> list[MappedPdo]:
    """Parse the whole-mapping syntax of one direction (``0x1600=controlword,0x607A:00/32;0x1601``)."""
    out: list[MappedPdo] = []
    parts = [p.strip() for p in text.split(";")]
    if not any(parts):
        return out  # "" = assign nothing
    used = list(taken or [])
    for part in parts:
        if not part:
            continue
        if "=" in part:
            idx_text, _, rest = part.partition("=")
            index = pdo_index(idx_text.strip(), location)
            entries = [parse_entry(e, device, location) for e in rest.split(",") if e.strip()]
            out.append(MappedPdo(index, entries, True, "", location))
        elif "," not in part and _is_pdo_index(part, direction):
            out.append(_device_pdo(pdo_index(part, location), direction, device, base, location))
        else:
            entries = [parse_entry(e, device, location) for e in part.split(",") if e.strip()]
            free = _first_free_pdo(direction, device, base, used + [p.index for p in out])
            if free is None:
                raise InputError(f"no free {direction.value.upper()} PDO for {part!r}; write 0x1600=… explicitly",
                                 location)
            out.append(MappedPdo(free, entries, True, "", location))
    return out


def _is_pdo_index(text: str, direction: Direction) -> bool:
    try:
        v = parse_int(text)
    except InputError:
        return False
    return pdo_direction(v) is not None and ":" not in text and "/" not in text


def _first_free_pdo(direction: Direction, device: Device | None, base: Mapping | None, used: list[int]) -> int | None:
    candidates: list[int] = []
    if base is not None:
        candidates += [p.index for p in base.pdos(direction)]
    if device is not None:
        candidates += [p.index for p in device.pdos(direction) if not p.fixed]
    candidates.append(RX_RANGE.start if direction is Direction.RX else TX_RANGE.start)
    for c in candidates:
        if c not in used:
            return c
    return None


# --- defaults --------------------------------------------------------------------------------------


def _mapping_from_dictionary(device: Device, index: int) -> list[PdoEntry] | None:
    """The entries a mapping object holds by default according to the dictionary's default values."""
    obj = device.dictionary.get(index)
    if obj is None:
        return None
    sub0 = obj.entry(0)
    count = sub0.default_value if sub0 is not None else None
    if not isinstance(count, int):
        return None
    out: list[PdoEntry] = []
    for k in range(1, count + 1):
        e = obj.entry(k)
        value = e.default_value if e is not None else None
        if not isinstance(value, int):
            return None
        pe = PdoEntry.from_mapping_value(value)
        out.append(_complete(pe, device, None))
    return out


def power_on_entries(device: Device, index: int) -> list[PdoEntry] | None:
    """The entries the dictionary's own mapping object ``index`` holds at power-on where the ESI's dictionary
    gives them (an object read from the file, with a count and a default for every entry it counts); None where
    the dictionary does not say (or its object was synthesised from the PDO list)."""
    obj = device.dictionary.get(index)
    if obj is None or obj.location is None or not obj.location.line:
        return None
    return _mapping_from_dictionary(device, index)


def _is_padding(value: int) -> bool:
    return (value >> 16) < 0x20  # a gap (index 0) or a dummy of a standard data type


def _padded_power_on(device: Device, index: int, listed: list[PdoEntry]) -> list[PdoEntry] | None:
    """The dictionary's own default mapping of ``index`` where it differs from the ESI's PDO list ``listed`` only
    by trailing padding (an EL6692's 1600h: a gap of 8 bits against an empty PDO): the same data, and the image
    the slave powers on with, padding included. None otherwise (the PDO list stands; where the two really
    differ, lint's PRJ027 says so)."""
    own = power_on_entries(device, index)
    if own is None:
        return None
    a, b = [e.mapping_value for e in own], [e.mapping_value for e in listed]
    if a == b:
        return None
    n = min(len(a), len(b))
    if a[:n] != b[:n] or not all(_is_padding(v) for v in (a[n:] or b[n:])):
        return None
    return own


def _pdo_entries(device: Device, pdo: Pdo) -> list[PdoEntry]:
    return [PdoEntry(e.index, e.subindex, e.bit_len, e.name, e.data_type, e.location) for e in pdo.entries]


def default_assignment(device: Device, direction: Direction) -> list[int]:
    """PDO indices assigned by default: the ESI PDOs with an ``Sm`` attribute or ``Mandatory`` (in file
    order), else the dictionary's 1C12h/1C13h defaults. A virtual PDO (``Virtual="true"``: ESC registers that
    TwinCAT maps through an FMMU, no CoE mapping object) is never assigned (docs/esi.md, "Virtual PDOs")."""
    pdos = [p.index for p in device.pdos(direction) if (p.sm is not None or p.mandatory) and not device.esc_registers(p)]
    if pdos:
        return pdos
    obj = device.dictionary.get(direction.assign_index)
    if obj is None:
        return []
    sub0 = obj.entry(0)
    count = sub0.default_value if sub0 is not None else None
    if not isinstance(count, int):
        return []
    out: list[int] = []
    for k in range(1, count + 1):
        e = obj.entry(k)
        v = e.default_value if e is not None else None
        if isinstance(v, int) and v:
            out.append(v)
    return out


def default_mapping(device: Device) -> Mapping:
    """The mapping a device has at power-on: default assignment with each PDO's default contents."""
    out = Mapping(source=device.source)
    for direction in Direction:
        pdos: list[MappedPdo] = []
        for index in default_assignment(device, direction):
            pdo = device.pdo(index)
            if pdo is not None:
                entries = _pdo_entries(device, pdo)
                own = _padded_power_on(device, index, entries)
                pdos.append(MappedPdo(index, entries if own is None else own, False, pdo.name, pdo.location))
            else:
                entries = _mapping_from_dictionary(device, index) or []
                pdos.append(MappedPdo(index, entries, False, "", None))
        out.set_pdos(direction, pdos)
    return out


def powered_on(device: Device, mapping: Mapping) -> tuple[Mapping, list[int]]:
    """``mapping`` as the slave holds it at power-on: each PDO kept as the device has it (not given with
    entries) whose mapping object's DefaultData contradicts the ESI's PDO element
    (:func:`ecattool.esi.power_on.contradictions`) takes the dictionary's entries, which the slave powers on with
    and every CoE master reads (the simulator serves them, the SII builder describes them). With the indices of
    those PDOs. A project is checked against the PDO element instead (lint's PRJ027 and
    ``esi-pdo-default-differs`` say where they differ; ``pdo:`` with entries programs the one meant)."""
    from ecattool.esi.power_on import contradictions

    differing = {c.pdo.index for c in contradictions(device)}
    changed: list[int] = []
    out = Mapping(given=set(mapping.given), source=mapping.source)
    for direction in Direction:
        pdos = []
        for p in mapping.pdos(direction):
            own = _mapping_from_dictionary(device, p.index) if not p.explicit and p.index in differing else None
            if own is None:
                pdos.append(p)
                continue
            changed.append(p.index)
            pdos.append(MappedPdo(p.index, own, False, p.name, p.location))
        out.set_pdos(direction, pdos)
    return out, changed


def virtual_pdos(device: Device, mapping: Mapping) -> list[MappedPdo]:
    """The PDOs of ``mapping`` that are windows onto ESC registers on ``device`` (:meth:`Device.esc_registers`,
    and no real PDO of that index): DC latch times, sync activation that TwinCAT puts into the process image
    through FMMUs. They are no sync manager's PDOs: never assigned, never counted against a sync manager."""
    out = []
    for d in Direction:
        for p in mapping.pdos(d):
            dev = device.pdo(p.index)
            if dev is not None and device.esc_registers(dev):
                out.append(p)
    return out


def without_virtual(device: Device, mapping: Mapping) -> tuple[Mapping, list[MappedPdo]]:
    """``mapping`` without its virtual PDOs (:func:`virtual_pdos`), and those left out."""
    gone = virtual_pdos(device, mapping)
    if not gone:
        return mapping, []
    ids = {id(p) for p in gone}
    out = Mapping(rx=[p for p in mapping.rx if id(p) not in ids], tx=[p for p in mapping.tx if id(p) not in ids],
                  given=set(mapping.given), source=mapping.source)
    return out, gone


# --- from a startup list ---------------------------------------------------------------------------


def mapping_from_startup(commands: Iterable[Any], device: Device | None = None, source: str = "") -> Mapping:
    """The mapping a startup list installs: its 1C12h/1C13h and mapping-object writes (single or complete
    access) applied in order over the device's power-on mapping. Directions whose assignment is never
    written keep the default; ``given`` holds the others. Commands are :class:`StartupCommand`-like objects
    (``index``, ``subindex``, ``data``, ``complete_access``, ``source``)."""
    base = default_mapping(device) if device is not None else Mapping()
    store: dict[tuple[int, int], int] = {}
    where: dict[tuple[int, int], Location | None] = {}
    written: set[int] = set()
    for cmd in commands:
        index, sub, data = cmd.index, cmd.subindex, bytes(cmd.data)
        kind = Direction.RX if index == 0x1C12 else Direction.TX if index == 0x1C13 else pdo_direction(index)
        if kind is None:
            continue
        written.add(index)
        loc = getattr(cmd, "source", None)
        if getattr(cmd, "complete_access", False) and sub == 0 and len(data) >= 2:
            width = 2 if index in (0x1C12, 0x1C13) else 4
            store[(index, 0)], where[(index, 0)] = data[0], loc
            body = data[2:]
            for k in range(len(body) // width):
                store[(index, k + 1)] = int.from_bytes(body[k * width:(k + 1) * width], "little")
                where[(index, k + 1)] = loc
        else:
            store[(index, sub)], where[(index, sub)] = int.from_bytes(data, "little"), loc
    out = Mapping(rx=list(base.rx), tx=list(base.tx), source=source or base.source)
    for direction in Direction:
        assign = direction.assign_index
        if assign not in written:
            continue
        pdos: list[MappedPdo] = []
        for k in range(1, store.get((assign, 0), 0) + 1):
            index = store.get((assign, k), 0)
            loc = where.get((assign, k))
            if index in written:
                entries = [
                    _complete(PdoEntry.from_mapping_value(store.get((index, s), 0)), device, where.get((index, s)))
                    for s in range(1, store.get((index, 0), 0) + 1)
                ]
                pdos.append(MappedPdo(index, entries, True, "", where.get((index, 0)) or loc))
            else:
                pdos.append(_device_pdo(index, direction, device, base, loc))
        out.set_pdos(direction, pdos)
        out.given.add(direction)
    return out


def programs_pdos(commands: Iterable[Any]) -> bool:
    """Whether a startup list writes the PDO assignment or a mapping object."""
    return any(c.index in (0x1C12, 0x1C13) or pdo_direction(c.index) is not None for c in commands)


def declared_mapping(config: Any, device: Device | None = None) -> Mapping | None:
    """The process data a master configuration declares (``SlaveConfig.rx_pdos``/``tx_pdos``: ros2 channels,
    ENI/ecmc entry lists), as an explicit mapping of the directions it lists; None when it lists none."""
    data = {
        d.value: [{"index": p.index, "entries": [e.mapping_value if e.index else f"gap/{e.bit_len}" for e in p.entries]}
                  for p in config.pdos(d)]
        for d in Direction if config.pdos(d)
    }
    if not data:
        return None
    locations: dict[tuple[str | int, ...], Location] = {(d.value, i, "entries", k): e.location
                 for d in Direction for i, p in enumerate(config.pdos(d)) for k, e in enumerate(p.entries)
                 if e.location is not None}
    locations.update({(d.value, i): p.location for d in Direction for i, p in enumerate(config.pdos(d))
                      if p.location is not None})
    return Mapping.from_data(data, device=device, locations=locations, source=_config_source(config))


def _config_source(config: Any) -> str:
    src = getattr(config, "source", None)
    return (src.file or "") if src is not None else ""


def mapping_from_config(config: Any, device: Device | None = None) -> Mapping:
    """The mapping a master configuration (:class:`ecattool.startup.SlaveConfig`) leaves the drive with: what
    its startup SDOs program when they touch 1C12h/1C13h or mapping objects, else what it declares (masters
    such as IgH/ros2 program declared PDOs themselves), else the device default."""
    if programs_pdos(config.commands):
        return mapping_from_startup(config.commands, device, source=_config_source(config))
    declared = declared_mapping(config, device)
    if declared is not None:
        return declared
    return default_mapping(device) if device is not None else Mapping()
