"""Static checks of a PDO mapping against a device and its family rules.

Every rule has a stable id (``PDO0nn``), one severity and a title; :data:`RULES` is the catalogue that
docs/pdo-mapping.md documents (a test keeps the two in step). :func:`check` returns the findings of one
mapping, each located where the PDO or entry was written.
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any

from ecattool.errors import EcatToolError, Location
from ecattool.esi.model import Device, Direction, Pdo, PdoEntry, with_article
from ecattool.findings import Finding, Severity
from ecattool.od.model import Entry
from ecattool.od.types import lookup
from ecattool.pdo.layout import layout
from ecattool.pdo.model import (
    RX_RANGE,
    TX_RANGE,
    MappedPdo,
    Mapping,
    declared_mapping,
    default_mapping,
    entry_keys,
    mapping_from_config,
    pdo_direction,
    power_on_entries,
    programs_pdos,
    without_virtual,
)
from ecattool.pdo.program import resolve_rules
from ecattool.profiles.rules import FamilyRules
from ecattool.startup.model import StartupCommand

E, W = Severity.ERROR, Severity.WARNING

#: rule id -> (severity, title)
RULES: dict[str, tuple[Severity, str]] = {
    "PDO000": (E, "the mapping text or data cannot be read"),
    "PDO001": (E, "the mapping object (PDO index) does not exist on the device"),
    "PDO002": (E, "a PDO of the other direction is assigned (RxPDO in 1C13h or TxPDO in 1C12h)"),
    "PDO003": (E, "the same PDO is assigned twice"),
    "PDO004": (E, "a mapped object does not exist in the dictionary"),
    "PDO005": (E, "a mapped sub-index does not exist"),
    "PDO006": (E, "the object cannot be mapped in this direction (PdoMapping R/T)"),
    "PDO007": (E, "the entry's bit length differs from the object's size"),
    "PDO008": (E, "an RxPDO entry is not writable or a TxPDO entry is not readable"),
    "PDO009": (E, "the PDO is longer than the family allows (bits per PDO)"),
    "PDO010": (E, "the PDO has more entries than the mapping object or family allows"),
    "PDO011": (E, "more PDOs are assigned than the sync manager assignment allows"),
    "PDO012": (E, "priority rule: a slow parameter is mapped in the first of two PDOs"),
    "PDO013": (E, "a gap or dummy entry is not allowed here"),
    "PDO014": (E, "a Fixed PDO's contents are changed"),
    "PDO015": (E, "a Mandatory PDO is not assigned"),
    "PDO016": (E, "two assigned PDOs exclude each other"),
    "PDO017": (E, "the PDO's Sm attribute names another sync manager"),
    "PDO018": (E, "the process image does not fit the sync manager"),
    "PDO019": (W, "a non-bit entry starts inside a byte (crosses a byte boundary)"),
    "PDO020": (W, "the same object is mapped twice"),
    "PDO021": (W, "an RxPDO object is also written by a startup SDO (the PDO overwrites it every cycle)"),
    "PDO022": (E, "the PDO assignment cannot be changed on this device"),
    "PDO023": (E, "the mapping object cannot be rewritten on this device"),
    "PDO024": (W, "an empty PDO is assigned"),
    "PDO025": (W, "an entry cannot be verified: the device has no object dictionary"),
    "PDO026": (E, "the entry's length is outside the family's entry size range"),
    "PDO027": (E, "the process image of a sync manager is not a whole number of bytes"),
    "PDO028": (W, "a master configuration declares other process data than its startup SDOs program"),
    "PDO029": (W, "a virtual PDO (ESC registers through an FMMU) is left out: no sync manager carries it"),
}

#: CiA-301 data-type indices usable as dummy entries, with their bit sizes
DUMMY_TYPE_BITS = {1: 1, 2: 8, 3: 16, 4: 32, 5: 8, 6: 16, 7: 32}


def rule_ids() -> list[str]:
    return sorted(RULES)


def input_finding(exc: EcatToolError) -> Finding:
    """A mapping that cannot be read, as a finding (rule PDO000) for reports that collect findings."""
    return _finding("PDO000", exc.message, exc.location)


def _finding(rule: str, message: str, location: Any, **data: Any) -> Finding:
    return Finding(rule, RULES[rule][0], message, location, data)


def _image(d: Direction, sm: int | None) -> str:
    """``output image (SM2)``: the image of one sync manager; without the SM number when the device has none
    for the direction (a finding never names a sync manager the device does not have)."""
    name = "output image" if d is Direction.RX else "input image"
    return name if sm is None else f"{name} (SM{sm})"


def _kind(d: Direction) -> str:
    return "RxPDO" if d is Direction.RX else "TxPDO"


def _a(index: int, sub: int | None = None) -> str:
    return f"0x{index:04X}" if sub is None else f"0x{index:04X}:{sub:02X}"


class _Checker:
    def __init__(self, device: Device, mapping: Mapping, rules: FamilyRules,
                 startup: Iterable[StartupCommand] | None) -> None:
        self.device = device
        self.mapping = mapping
        self.rules = rules
        self.startup = list(startup or [])
        self.od = device.dictionary
        self.default = default_mapping(device)
        self.out: list[Finding] = []
        #: assigned PDO indices already reported as unknown (PDO001)
        self.bad: set[int] = set()
        #: PDOs assigned to the wrong sync manager -> their own direction (their contents are judged as such)
        self.wrong: dict[int, Direction] = {}
        #: entries the device's own PDOs map, per direction (index, sub, bits): legal by evidence
        self.known_entries: dict[Direction, set[tuple[int, int, int]]] = {
            d: {(e.index, e.subindex, e.bit_len) for p in device.pdos(d) for e in p.entries if e.index}
            for d in Direction
        }

    def add(self, rule: str, message: str, location: Any, **data: Any) -> None:
        if location is None:
            location = self.mapping_location()
        self.out.append(_finding(rule, message, location, **data))

    # --- PDO level --------------------------------------------------------------------------------
    def known_pdos(self, d: Direction) -> set[int]:
        family = self.rules.rx_mapping_indices if d is Direction.RX else self.rules.tx_mapping_indices
        known = {p.index for p in self.device.pdos(d)} | set(family)
        rng = RX_RANGE if d is Direction.RX else TX_RANGE
        if not family:
            known |= {i for i in self.od.indices() if i in rng}
        known |= {p.index for p in self.default.pdos(d)}
        return known

    def check_assignment(self, d: Direction) -> None:
        pdos = self.mapping.pdos(d)
        other = Direction.TX if d is Direction.RX else Direction.RX
        known, known_other = self.known_pdos(d), self.known_pdos(other)
        seen: set[int] = set()
        for p in pdos:
            if p.index in seen:
                self.add("PDO003", f"PDO {_a(p.index)} is assigned twice to 0x{d.assign_index:04X}", p.location,
                         pdo=p.index)
            seen.add(p.index)
            if p.index not in known:
                if p.index in known_other or pdo_direction(p.index) is other:
                    self.wrong[p.index] = other
                    article = "an" if other is Direction.RX else "a"
                    self.add("PDO002", f"{_a(p.index)} is {article} {_kind(other)}; it cannot be assigned to "
                             f"0x{d.assign_index:04X}", p.location, pdo=p.index)
                else:
                    self.bad.add(p.index)
                    choices = ", ".join(_a(i) for i in sorted(known)) or "none"
                    self.add("PDO001", f"{_a(p.index)} is not a {_kind(d)} mapping object of "
                             f"{self.device.type_name} (known: {choices})", p.location, pdo=p.index)
            dev_pdo = self.device.pdo(p.index)
            if dev_pdo is not None and p.index not in self.bad:
                self.check_device_pdo(d, p, dev_pdo, sm_check=p.index not in self.wrong)
        # assignment size
        limit = self.rules.max_assigned_rx if d is Direction.RX else self.rules.max_assigned_tx
        assign_entries = self.rules.max_assign_entries
        if assign_entries is not None and (limit is None or assign_entries < limit):
            limit = assign_entries
        obj = self.od.get(d.assign_index)
        od_limit = obj.max_subindex if obj is not None and obj.max_subindex > 0 else None
        # the assignment object governs the direction's first process-data SM; PDOs whose Sm attribute puts them
        # on another SM of the same direction (outputs over SM0, SM1 and SM2) are not in its list
        first = self.device.process_sm(d)
        counted = [p for p in pdos if first is None or self.sm_of(d, p.index) == first.number]
        for lim, why in ((limit, f"the {self.rules.family} family"), (od_limit, f"0x{d.assign_index:04X}")):
            if lim is not None and len(counted) > lim:
                self.add("PDO011", f"{len(counted)} PDOs assigned to 0x{d.assign_index:04X}; {why} allows at most "
                         f"{lim}", counted[lim].location, count=len(counted), limit=lim)
                break
        # mandatory and exclude
        assigned = {p.index for p in pdos}
        for dev_pdo in self.device.pdos(d):
            if dev_pdo.mandatory and dev_pdo.index not in assigned and not self.device.esc_registers(dev_pdo):
                self.add("PDO015", f"PDO {_a(dev_pdo.index)} ({dev_pdo.name}) is Mandatory but not assigned",
                         pdos[0].location if pdos else self.mapping_location(), pdo=dev_pdo.index)
        reported: set[frozenset[int]] = set()
        for p in pdos:
            dev_pdo = self.device.pdo(p.index)
            for x in dev_pdo.excludes if dev_pdo is not None else []:
                pair = frozenset((p.index, x))
                if x in assigned and x != p.index and pair not in reported:
                    reported.add(pair)
                    self.add("PDO016", f"PDO {_a(p.index)} excludes {_a(x)}; assign only one of them", p.location,
                             pdo=p.index, excludes=x)
        # writability of the assignment
        if [p.index for p in pdos] != [p.index for p in self.default.pdos(d)]:
            why = self.assign_not_writable(d)
            if why:
                self.add("PDO022", f"the {_kind(d)} assignment differs from the default but {why}",
                         pdos[0].location if pdos else self.mapping_location())

    def mapping_location(self) -> Any:
        """Where a finding without an entry or PDO of its own points: the mapping's file, else the device."""
        if self.mapping.source:
            return Location(self.mapping.source)
        return self.device.location or (Location(self.device.source) if self.device.source else None)

    def assign_not_writable(self, d: Direction) -> str:
        if not self.rules.assign_writable:
            return f"{self.family_text()} does not allow changing 0x{d.assign_index:04X}"
        if not self.device.has_coe:
            return f"the device has no CoE mailbox to write 0x{d.assign_index:04X}"
        obj = self.od.get(d.assign_index)
        if obj is not None and not any(e.access.writable() for e in obj.entries.values()):
            return f"0x{d.assign_index:04X} is read-only"
        return ""

    def mapping_not_writable(self, index: int) -> str:
        if not self.rules.mapping_writable:
            return f"{self.family_text()} does not allow rewriting mapping objects"
        if not self.device.has_coe:
            return "the device has no CoE mailbox"
        sub0 = self.od.entry(index, 0)
        if sub0 is not None and not sub0.access.writable():
            return f"{_a(index, 0)} is read-only"
        return ""

    def family_text(self) -> str:
        if self.rules.family == "generic":
            return f"{self.device.type_name} (its ESI: CoE PdoAssign/PdoConfig, Fixed PDOs)"
        return f"the {self.rules.family} family"

    def sm_of(self, d: Direction, index: int) -> int | None:
        """The sync manager that carries PDO ``index`` in direction ``d``: the one its ``Sm`` attribute names when
        that is a process-data sync manager of this direction (a terminal may spread its outputs over SM0, SM1
        and SM2 by design), else the direction's first one (SM2/SM3 usually); None when the device has none."""
        dev_pdo = self.device.pdo(index)
        if dev_pdo is not None and dev_pdo.sm is not None:
            sm = self.device.sm(dev_pdo.sm)
            if sm is not None and sm.kind == d.sm_kind and not sm.virtual:
                return sm.number
        first = self.device.process_sm(d)
        return first.number if first is not None else None

    def check_device_pdo(self, d: Direction, p: MappedPdo, dev_pdo: Pdo, sm_check: bool = True) -> None:
        if sm_check and dev_pdo.sm is not None and self.device.process_sm(d) is not None:
            sm = self.device.sm(dev_pdo.sm)
            if sm is None:
                self.add("PDO017", f"PDO {_a(p.index)} names SM{dev_pdo.sm} (Sm attribute), which the device does "
                         f"not have", p.location, pdo=p.index, sm=dev_pdo.sm)
            elif sm.kind != d.sm_kind:
                what = with_article(sm.kind) if sm.kind else "an unused"
                self.add("PDO017", f"PDO {_a(p.index)} belongs to SM{dev_pdo.sm} (Sm attribute), {what} sync "
                         f"manager, not {with_article(d.sm_kind)} one", p.location, pdo=p.index, sm=dev_pdo.sm)
        if dev_pdo.fixed and p.explicit and entry_keys(p.entries) != entry_keys(dev_pdo.entries):
            self.add("PDO014", f"PDO {_a(p.index)} ({dev_pdo.name}) is Fixed; its entries cannot be changed "
                     f"(omit 'entries' to assign it as it is)", p.location, pdo=p.index)

    # --- entry level ------------------------------------------------------------------------------
    def check_pdo(self, d: Direction, p: MappedPdo, first_of_two: bool) -> None:
        if p.index in self.bad and not p.entries:
            return  # reported as unknown already
        if p.index in self.wrong:  # assigned to the wrong SM: its contents are still written to its object
            d, first_of_two = self.wrong[p.index], False
        if not p.entries:
            self.add("PDO024", f"PDO {_a(p.index)} is assigned with no entries", p.location, pdo=p.index)
        if not p.explicit:
            return  # the device's own contents: limits and entry rules are the ESI's/profile's business
        bits = p.bit_size
        if self.rules.max_pdo_bits is not None and bits > self.rules.max_pdo_bits:
            self.add("PDO009", f"PDO {_a(p.index)} has {bits} bits; {self.rules.family} allows at most "
                     f"{self.rules.max_pdo_bits} bits per PDO", p.location, pdo=p.index, bits=bits)
        obj = self.od.get(p.index)
        od_limit = max((k for k in obj.entries if k > 0), default=0) if obj is not None else 0
        for lim, why in ((self.rules.max_pdo_entries, f"the {self.rules.family} family"),
                         (od_limit or None, f"mapping object {_a(p.index)}")):
            if lim is not None and len(p.entries) > lim:
                self.add("PDO010", f"PDO {_a(p.index)} has {len(p.entries)} entries; {why} allows at most {lim}",
                         p.entries[lim].location or p.location, pdo=p.index, entries=len(p.entries), limit=lim)
                break
        dev_pdo = self.device.pdo(p.index)
        if p.index not in self.bad and not (dev_pdo is not None and dev_pdo.fixed):
            current = next((q for q in self.default.pdos(d) if q.index == p.index), None)
            reference = current.entries if current is not None else (dev_pdo.entries if dev_pdo is not None else None)
            held = power_on_entries(self.device, p.index)
            if held is not None:
                reference = held  # the slave powers on with its dictionary's own mapping: that is what is rewritten
            if reference is None or entry_keys(reference) != entry_keys(p.entries):
                why = self.mapping_not_writable(p.index)
                if not why and current is not None and self.assign_not_writable(d):
                    why = f"it is assigned by default and {self.assign_not_writable(d)}"
                if why:
                    self.add("PDO023", f"PDO {_a(p.index)} cannot be rewritten: {why}", p.location, pdo=p.index)
        for e in p.entries:
            self.check_entry(d, p, e, first_of_two)

    def check_entry(self, d: Direction, p: MappedPdo, e: PdoEntry, first_of_two: bool) -> None:
        loc = e.location or p.location
        rx = d is Direction.RX
        if e.is_gap:
            if not self.rules.gaps_allowed:
                hint = ""
                if rx and self.rules.dummies_in_rx and self.rules.dummy_indices:
                    hint = " (pad with a dummy entry instead, e.g. 0x0005:00/8)"
                self.add("PDO013", f"gap entry ({e.bit_len} bits) in {_a(p.index)}: {self.rules.family} does not "
                         f"allow gaps (index 0) in mapping objects{hint}", loc, pdo=p.index)
            return
        if self.is_dummy(e.index):
            allowed = self.rules.dummies_in_rx if rx else self.rules.dummies_in_tx
            if not allowed:
                self.add("PDO013", f"dummy entry {_a(e.index, e.subindex)} in {_kind(d)} {_a(p.index)}: "
                         f"dummies are allowed only in {'TxPDOs' if rx else 'RxPDOs'}", loc, pdo=p.index)
                return
            size = self.dummy_bits(e.index)
            if size is not None and e.bit_len != size:
                self.add("PDO007", f"dummy {_a(e.index, e.subindex)} is {size} bits, mapped with {e.bit_len}", loc,
                         pdo=p.index, expected=size, given=e.bit_len)
            return
        if first_of_two and self.rules.priority_rule and self.is_slow(e.index, self.od.entry(e.index, e.subindex)):
            self.add("PDO012", f"{_a(e.index, e.subindex)} ({e.name}) is a slow parameter; with two {_kind(d)}s it "
                     f"must be in the second PDO, not in {_a(p.index)}", loc, index=e.index, subindex=e.subindex)
        if (e.index, e.subindex, e.bit_len) in self.known_entries[d]:
            return  # the device maps exactly this entry in one of its own PDOs of this direction
        if not len(self.od):
            self.add("PDO025", f"{_a(e.index, e.subindex)} cannot be verified: {self.device.type_name} has "
                     "no object dictionary", loc, pdo=p.index)
            return
        obj = self.od.get(e.index)
        if obj is None:
            self.add("PDO004", f"object {_a(e.index)} does not exist in {self.device.type_name}", loc,
                     index=e.index)
            return
        entry = obj.entry(e.subindex)
        if entry is None:
            subs = ", ".join(f"{k:02X}" for k in sorted(obj.entries)) or "none"
            self.add("PDO005", f"{_a(e.index, e.subindex)}: object {obj.name!r} has no sub-index "
                     f"{e.subindex:02X} (has {subs})", loc, index=e.index, subindex=e.subindex)
            return
        label = f"{_a(e.index, e.subindex)} ({e.name or entry.name})"
        lo, hi = self.rules.min_entry_bits, self.rules.max_entry_bits
        if (lo is not None and e.bit_len < lo) or (hi is not None and e.bit_len > hi):
            self.add("PDO026", f"{label} has {e.bit_len} bits; {self.rules.family} maps entries of "
                     f"{lo or 1}..{hi or 255} bits", loc, bits=e.bit_len)
        if e.bit_len != entry.bit_size:
            self.add("PDO007", f"{label} is {entry.type_name or '?'} of {entry.bit_size} bits, mapped with "
                     f"{e.bit_len} bits (write {_a(e.index, e.subindex)}/{entry.bit_size})", loc,
                     expected=entry.bit_size, given=e.bit_len)
        self.check_direction(d, label, entry, e, loc)

    def check_direction(self, d: Direction, label: str, entry: Entry, e: PdoEntry, loc: Any) -> None:
        rx = d is Direction.RX
        flag = entry.pdo_mapping
        if e.index in self.rules.sdo_only_indices:
            self.add("PDO006", f"{label} can only be accessed by SDO on {self.rules.family} drives", loc,
                     index=e.index, subindex=e.subindex, pdo_mapping="")
            return
        if ("R" if rx else "T") not in flag:
            where = {"R": "mappable in RxPDOs only", "T": "mappable in TxPDOs only"}.get(flag, "not mappable")
            self.add("PDO006", f"{label} is {where} (PdoMapping {flag or 'none'}); it cannot be mapped in a "
                     f"{_kind(d)}", loc, index=e.index, subindex=e.subindex, pdo_mapping=flag)
            return
        if flag != "RT":
            return  # a one-direction flag is the vendor's word: trust it over the access column
        if rx and not entry.access.writable():
            self.add("PDO008", f"{label} is {entry.access.text} and cannot be written by an RxPDO", loc,
                     index=e.index, subindex=e.subindex)
        elif not rx and not entry.access.readable():
            self.add("PDO008", f"{label} is {entry.access.text} and cannot be read by a TxPDO", loc,
                     index=e.index, subindex=e.subindex)

    def is_dummy(self, index: int) -> bool:
        if index in self.rules.dummy_indices:
            return True
        return index in DUMMY_TYPE_BITS and index not in self.od and bool(self.rules.dummy_indices)

    def dummy_bits(self, index: int) -> int | None:
        entry = self.od.entry(index, 0)
        if entry is not None:
            return entry.bit_size
        return DUMMY_TYPE_BITS.get(index)

    def is_slow(self, index: int, entry: Entry | None) -> bool:
        """A slow parameter (Control Techniques priority rule): the dictionary marks it (category "slow")."""
        if index in self.rules.slow_indices:
            return True
        obj = self.od.get(index)
        marks = (entry.category if entry is not None else "", obj.category if obj is not None else "")
        return any(m.strip().lower() == "slow" for m in marks)

    # --- image level ------------------------------------------------------------------------------
    def sm_groups(self, d: Direction, pdos: list[MappedPdo]) -> list[tuple[int | None, list[MappedPdo]]]:
        """The assigned PDOs of ``d`` per sync manager, in the order of their first PDO (one group, the
        direction's first process-data SM, unless PDOs name other SMs of the same direction)."""
        groups: dict[int | None, list[MappedPdo]] = {}
        for p in pdos:
            groups.setdefault(self.sm_of(d, p.index), []).append(p)
        return list(groups.items())

    def pad_hint(self, d: Direction, pdos: list[MappedPdo], pad: int) -> str | None:
        """How to pad an image of whole PDOs to whole bytes, or None when nothing can be done: every PDO of the
        image is Fixed or its mapping object cannot be written (a device with no mailbox, a fixed 2-bit input
        terminal: its sync manager simply carries the bits it has, as the ESC maps them bit by bit)."""
        changeable = [p for p in pdos if p.index not in self.bad and not self.mapping_not_writable(p.index)
                      and not ((dp := self.device.pdo(p.index)) is not None and dp.fixed)]
        if not changeable:
            return None
        if self.rules.gaps_allowed:
            return f"add a gap of {pad} bits (gap/{pad})"
        if self.rules.dummy_indices and (self.rules.dummies_in_rx if d is Direction.RX else self.rules.dummies_in_tx):
            return f"pad it with {pad} bits of dummy entries ({self.rules.family} allows no gaps)"
        return f"map {pad} more bits ({self.rules.family} allows no gaps)"

    def check_image(self) -> None:
        lay = layout(self.device, self.mapping)
        for d in Direction:
            img = lay.image(d)
            pdos = self.mapping.pdos(d)
            if img.bit_size and self.device.process_sm(d) is None and self.device.sync_managers:
                self.add("PDO018", f"the device has no {d.sm_kind} sync manager for {img.byte_size} bytes of "
                         f"{_kind(d)} process data", pdos[0].location if pdos else None, bytes=img.byte_size)
            # bit offsets inside each sync manager's own image
            where: dict[int, tuple[int | None, int]] = {}  # id of a PDO entry -> (SM, bit offset in that SM)
            for sm_no, group in self.sm_groups(d, pdos):
                bits = 0
                for p in group:
                    for e in p.entries:
                        where[id(e)] = (sm_no, bits)
                        bits += e.bit_len
                loc = group[0].location
                sm = self.device.sm(sm_no) if sm_no is not None else None
                size = (bits + 7) // 8
                if sm is not None and sm.max_size is not None and size > sm.max_size:
                    self.add("PDO018", f"the {_image(d, sm_no)} is {size} bytes; SM{sm_no} holds at most "
                             f"{sm.max_size} bytes", loc, bytes=size, max=sm.max_size)
                hint = self.pad_hint(d, group, 8 - bits % 8) if bits % 8 else None
                if hint is not None:
                    self.add("PDO027", f"the {_image(d, sm_no)} is {bits} bits, not a whole number of bytes; {hint}",
                             loc, bits=bits)
            by_pdo = {p.index: p for p in pdos}
            seen: dict[tuple[int, int], int] = {}
            # every mapped RxPDO object is overwritten every cycle, default PDOs included
            mapped_rx: dict[tuple[int, int], int] = {}
            for ie, src in zip(img.entries, (e for p in pdos for e in p.entries)):
                if ie.is_gap:
                    continue
                mapped_rx.setdefault((ie.index, ie.subindex), ie.pdo)
                pdo = by_pdo.get(ie.pdo)
                if pdo is None or not pdo.explicit:
                    continue
                eloc = src.location or pdo.location
                sm_no, bit_offset = where.get(id(src), (img.sm, ie.bit_offset))
                dt = lookup(ie.type_name) if ie.type_name else None
                bit_type = ie.bit_len < 8 or (dt is not None and dt.is_bit_type)
                if bit_offset % 8 and not bit_type:
                    self.add("PDO019", f"{_a(ie.index, ie.subindex)} starts at bit {bit_offset // 8}.{bit_offset % 8} "
                             f"of the {_image(d, sm_no)}; a {ie.bit_len}-bit value should start on a byte boundary",
                             eloc, offset=f"{bit_offset // 8}.{bit_offset % 8}")
                key = (ie.index, ie.subindex)
                if self.is_dummy(ie.index):
                    continue  # dummies pad a PDO and carry no data: repeating one is how they are used (§2.3.1)
                if key in seen:
                    self.add("PDO020", f"{_a(*key)} is mapped twice in the {_image(d, img.sm)} "
                             f"(PDO {_a(seen[key])} and {_a(ie.pdo)})", eloc, index=ie.index, subindex=ie.subindex)
                seen[key] = ie.pdo
            if d is Direction.RX:
                self.check_startup_overlap(mapped_rx, pdos)

    def check_startup_overlap(self, mapped: dict[tuple[int, int], int], pdos: list[MappedPdo]) -> None:
        locs = {(e.index, e.subindex): e.location or p.location for p in pdos for e in p.entries}
        for cmd in self.startup:
            hits = [k for k in mapped if k[0] == cmd.index and (k[1] == cmd.subindex or cmd.complete_access)]
            for key in hits:
                self.add("PDO021", f"{_a(*key)} is mapped in RxPDO {_a(mapped[key])} and also written by a startup "
                         f"SDO ({cmd.transition}); the PDO overwrites it every cycle",
                         cmd.source or locs.get(key), index=key[0], subindex=key[1])

    def run(self) -> list[Finding]:
        for d in Direction:
            self.check_assignment(d)
            pdos = self.mapping.pdos(d)
            for i, p in enumerate(pdos):
                self.check_pdo(d, p, first_of_two=(i == 0 and len(pdos) >= 2))
        self.check_image()
        return self.out


def check(
    device: Device,
    mapping: Mapping,
    rules: FamilyRules | None = None,
    startup: Iterable[StartupCommand] | None = None,
) -> list[Finding]:
    """All findings of ``mapping`` on ``device`` (see :data:`RULES`). ``startup`` are the other startup
    commands of the drive (for PDO021)."""
    mapping, virtual = without_virtual(device, mapping)
    notes = [_finding("PDO029", f"PDO {_a(p.index)} ({p.name or 'virtual'}) is a virtual PDO of {device.type_name}: "
                      "ESC registers TwinCAT maps through an FMMU, not a PDO of a sync manager; it is left out of the "
                      "assignment and the process image (read the registers directly)", p.location, pdo=p.index)
             for p in virtual]
    return notes + _Checker(device, mapping, resolve_rules(device, rules), startup).run()


def check_config(
    device: Device, config: Any, rules: FamilyRules | None = None
) -> tuple[Mapping, list[Finding]]:
    """Check a master configuration (:class:`ecattool.startup.SlaveConfig`): the mapping it leaves the drive
    with (:func:`ecattool.pdo.model.mapping_from_config`), its other startup SDOs (PDO021), and whether the
    entries it declares sit where its startup SDOs put them (PDO028)."""
    mapping = mapping_from_config(config, device)
    others = [c for c in config.commands if c.index not in (0x1C12, 0x1C13) and pdo_direction(c.index) is None]
    findings = check(device, mapping, rules=rules, startup=others)
    declared = declared_mapping(config, device) if programs_pdos(config.commands) else None
    if declared is not None:
        lay, dec = layout(device, mapping), layout(device, declared)
        for d in Direction:
            if d not in declared.given:
                continue
            actual = {(e.index, e.subindex): e for e in lay.image(d).entries if not e.is_gap}
            where_declared = {(e.index, e.subindex): e.location or p.location
                              for p in declared.pdos(d) for e in p.entries}
            for e in dec.image(d).entries:
                a = actual.get((e.index, e.subindex))
                if e.is_gap or (a is not None and a.bit_offset == e.bit_offset and a.bit_len == e.bit_len):
                    continue
                where = f"at {a.offset} in PDO {_a(a.pdo)}" if a is not None else "nowhere"
                findings.append(_finding(
                    "PDO028", f"{_a(e.index, e.subindex)} is declared at {e.offset} in PDO {_a(e.pdo)} of the "
                    f"{_image(d, lay.image(d).sm)}, but the startup SDOs map it {where}",
                    where_declared.get((e.index, e.subindex)) or (Location(mapping.source) if mapping.source else None),
                    index=e.index, subindex=e.subindex, declared=e.offset, actual=a.offset if a else None))
    return mapping, findings
