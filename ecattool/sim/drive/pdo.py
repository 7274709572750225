"""PDO configuration objects: what the drive accepts in the mapping objects (1600h-17FFh, 1A00h-1BFFh) and
the assignment objects (1C12h/1C13h) per its family rules, and the abort code it answers otherwise."""

from __future__ import annotations

from typing import TYPE_CHECKING

from ecattool import abort as A
from ecattool.esi.model import Direction, PdoEntry
from ecattool.od.model import EcState
from ecattool.od.types import lookup
from ecattool.sim.drive.core import RX, TX, sdo_abort

if TYPE_CHECKING:
    from ecattool.sim.drive.app import DriveApp


def is_mapping(index: int) -> Direction | None:
    if 0x1600 <= index <= 0x17FF:
        return RX
    if 0x1A00 <= index <= 0x1BFF:
        return TX
    return None


_ASSIGN = {0x1C12: RX, 0x1C13: TX}


def is_assign(index: int) -> Direction | None:
    return _ASSIGN.get(index)


class PdoConfig:
    """The PDO configuration part: the entries the slave can map, the defaults at power-on, mapping and assignment
    writes with the family's rules (the SDO server and the process data part both use it)."""

    __slots__ = ("drive",)

    def __init__(self, drive: DriveApp) -> None:
        self.drive = drive

    def known_entries(self) -> dict[Direction, set[tuple[int, int, int]]]:
        """The entries the slave maps whatever the dictionary's flags say: those of the ESI's PDO list, and those
        of its dictionary's own default mapping that name an object of the dictionary at its size (a vendor ESI
        often leaves PdoMapping off objects its firmware maps by default: Synapticon's 607Ah). A default entry
        of a data type index (a dummy) or of an object that does not exist is not known: it is checked, and
        refused, as any written entry is."""
        drive = self.drive
        known: dict[Direction, set[tuple[int, int, int]]] = {RX: set(), TX: set()}
        od = drive.device.dictionary
        for d in (RX, TX):
            for pdo in drive.device.pdos(d):
                for e in pdo.entries:
                    if e.index:
                        known[d].add((e.index, e.subindex, e.bit_len))
            first = 0x1600 if d is RX else 0x1A00
            for obj in od:
                if not first <= obj.index <= first + 0x1FF:
                    continue
                for sub, me in obj.entries.items():
                    if not sub or me.default is None or len(me.default) != 4:
                        continue
                    v = int.from_bytes(me.default, "little")
                    idx, s, bits = v >> 16, (v >> 8) & 0xFF, v & 0xFF
                    target = od.entry(idx, s) if idx >= 0x20 else None
                    if target is not None and target.bit_size == bits:
                        known[d].add((idx, s, bits))
        return known

    def _own_mapping(self, index: int) -> bool:
        """Whether the dictionary's mapping object ``index`` gives its own power-on mapping: a default for the
        count and for every entry it counts. A slave stack (SOES and the like) powers on with its dictionary, not
        with the ESI's PDO list, so where the two differ the slave runs the dictionary's mapping and refuses
        SAFE-OP for an entry it cannot map (lint's PRJ027). Only the CoE mapping objects (1600h-17FFh,
        1A00h-1BFFh) count: a PDO list that names another index (an EL1262's 1C00h) is the ESI's alone."""
        drive = self.drive
        if not (0x1600 <= index <= 0x17FF or 0x1A00 <= index <= 0x1BFF):
            return False
        count = drive.objects.entries.get((index, 0))
        if count is None or not count.default:
            return False
        n = int.from_bytes(count.default, "little")
        return all((e := drive.objects.entries.get((index, s))) is not None and bool(e.default) for s in range(1, n + 1))

    def defaults(self) -> None:
        """Mapping objects hold the dictionary's own defaults where it gives them (:meth:`_own_mapping`), else the
        device's PDO entries; 1C12h/1C13h its default assignment (PDO@Sm)."""
        drive = self.drive
        for d in (RX, TX):
            pdos = drive.device.pdos(d)
            for pdo in pdos:
                if drive.device.esc_registers(pdo) or (pdo.index, 0) not in drive.objects.entries or self._own_mapping(pdo.index):
                    continue
                for i, e in enumerate(pdo.entries, start=1):
                    if (pdo.index, i) in drive.objects.entries:
                        drive.objects.store[(pdo.index, i)] = e.mapping_value.to_bytes(4, "little")
                drive._put(pdo.index, 0, len(pdo.entries))
            assign = d.assign_index
            if (assign, 0) in drive.objects.entries and any(p.sm is not None and not drive.device.esc_registers(p) for p in pdos):
                chosen = [p.index for p in pdos if p.sm is not None and not drive.device.esc_registers(p)]
                subs = sorted(s for (i, s) in drive.objects.entries if i == assign and s > 0)
                for s in subs:
                    drive.objects.store[(assign, s)] = b"\x00\x00"
                for s, index in zip(subs, chosen):
                    drive.objects.store[(assign, s)] = index.to_bytes(2, "little")
                drive._put(assign, 0, min(len(chosen), len(subs)))

    def _assigned(self, d: Direction) -> list[int]:
        drive = self.drive
        assign = d.assign_index
        if (assign, 0) not in drive.objects.entries:  # a virtual PDO is ESC registers: the slave assigns no such PDO
            return [p.index for p in drive.device.pdos(d) if p.sm is not None and not drive.device.esc_registers(p)]
        n = drive._read_int(assign, 0) or 0
        chosen = (drive._read_int(assign, s) or 0 for s in range(1, n + 1) if (assign, s) in drive.objects.entries)
        return [p for p in chosen if p]  # a 0 entry assigns nothing (Technosoft §2.5 leaves sub 2 at 0)

    def _mapping_write(self, d: Direction, index: int, sub: int, value: int) -> None:
        drive = self.drive
        if not drive.rules.mapping_writable or index in drive._fixed:
            raise sdo_abort(index, sub, A.READ_ONLY)
        if drive.esm is not EcState.PREOP:
            raise sdo_abort(index, sub, A.DATA_CANNOT_BE_STORED_STATE)
        if drive.behaviour.mapping_assigned is not None and index in self._assigned(d):
            raise sdo_abort(index, sub, drive.behaviour.mapping_assigned)
        if sub == 0:
            self._check_mapping_count(d, index, value)
            return
        if drive.rules.mapping_write_needs_sub0_zero and drive._read_int(index, 0):
            raise sdo_abort(index, sub, drive.behaviour.mapping_busy)
        if value:
            self._mapping_entry_bits(d, index, sub, value)

    def _mapping_entry_bits(self, d: Direction, index: int, sub: int, value: int) -> int:
        """Check one mapping entry value; returns its bit length or raises the drive's abort."""
        drive = self.drive
        idx, s, bits = value >> 16, (value >> 8) & 0xFF, value & 0xFF
        if bits == 0:
            raise sdo_abort(index, sub, A.NOT_MAPPABLE)
        if idx == 0:
            if not drive.rules.gaps_allowed:
                raise sdo_abort(index, sub, A.NOT_MAPPABLE)
            return bits
        if idx in drive.rules.dummy_indices or (idx < 0x20 and (idx, s) not in drive.objects.entries):
            allowed = drive.rules.dummies_in_rx if d is RX else drive.rules.dummies_in_tx
            if idx not in drive.rules.dummy_indices or not allowed:
                raise sdo_abort(index, sub, A.NOT_MAPPABLE if idx in drive.rules.dummy_indices else A.OBJECT_DOES_NOT_EXIST)
            e = drive.objects.entries.get((idx, s))
            dt = lookup(idx) if idx < 0x20 else None
            size = e.bit_size if e is not None else (dt.bits if dt is not None else None)
            if size is not None and size != bits:
                raise sdo_abort(index, sub, A.NOT_MAPPABLE)
            return bits
        if (idx, s, bits) in drive._pdo_known[d]:
            return bits
        e = drive.objects.entries.get((idx, s))
        if e is None:
            raise sdo_abort(index, sub, A.OBJECT_DOES_NOT_EXIST)
        if not (e.rx_mappable if d is RX else e.tx_mappable) or e.bit_size != bits:
            raise sdo_abort(index, sub, A.NOT_MAPPABLE)
        return bits

    def _check_mapping_count(self, d: Direction, index: int, n: int) -> None:
        drive = self.drive
        if n == 0:
            return
        subs = [s for s in range(1, n + 1)]
        if any((index, s) not in drive.objects.entries for s in subs):
            raise sdo_abort(index, 0, A.VALUE_TOO_HIGH)
        if drive.rules.max_pdo_entries is not None and n > drive.rules.max_pdo_entries:
            raise sdo_abort(index, 0, A.PDO_LENGTH_EXCEEDED)
        if not drive.rules.mapping_write_needs_sub0_zero:
            return  # entries may follow sub-index 0 (Control Techniques 5.1.3); SAFE-OP checks the result
        total = 0
        for s in subs:
            v = drive._read_int(index, s) or 0
            if not v:
                raise sdo_abort(index, 0, A.GENERAL_PARAMETER_INCOMPATIBILITY)
            total += self._mapping_entry_bits(d, index, 0, v)
        limit = drive.rules.max_pdo_bits
        if limit is not None and total > limit and drive.strict_pdo_length:
            raise sdo_abort(index, 0, A.PDO_LENGTH_EXCEEDED)

    def _assign_write(self, d: Direction, index: int, sub: int, value: int) -> None:
        drive = self.drive
        if not drive.rules.assign_writable:
            raise sdo_abort(index, sub, A.READ_ONLY)
        if drive.esm is not EcState.PREOP:
            raise sdo_abort(index, sub, A.DATA_CANNOT_BE_STORED_STATE)
        if sub == 0:
            if value == 0:
                return
            limit = drive.rules.max_assigned_rx if d is RX else drive.rules.max_assigned_tx
            if limit is not None and value > limit:
                raise sdo_abort(index, 0, A.VALUE_TOO_HIGH)
            chosen = [drive._read_int(index, s) or 0 for s in range(1, value + 1) if (index, s) in drive.objects.entries]
            if len(chosen) != value:
                raise sdo_abort(index, 0, A.VALUE_TOO_HIGH)
            chosen = [p for p in chosen if p]
            if any(not self._valid_pdo_index(d, p) for p in chosen) or len(set(chosen)) != len(chosen):
                raise sdo_abort(index, 0, A.INVALID_VALUE)
            if self._slow_in_first(d, chosen):
                raise sdo_abort(index, 0, A.GENERAL_PARAMETER_INCOMPATIBILITY)
            return
        if drive.rules.assign_write_needs_sub0_zero and drive._read_int(index, 0):
            raise sdo_abort(index, sub, drive.behaviour.assign_busy)
        if value and not self._valid_pdo_index(d, value):
            raise sdo_abort(index, sub, A.INVALID_VALUE)

    def _slow_in_first(self, d: Direction, chosen: list[int]) -> bool:
        """Control Techniques 6.1.1: with two PDOs in a sync manager, slow parameters (SM-Applications,
        Inter-Option) may only be in the second (low priority) one; in the first the drive aborts."""
        drive = self.drive
        if not drive.rules.priority_rule or len(chosen) < 2:
            return False
        slow = drive.rules.slow_indices
        return any(e.index in slow for e in self._pdo_entries(d, chosen[0]) or [])

    def _valid_pdo_index(self, d: Direction, pdo: int) -> bool:
        drive = self.drive
        allowed = drive.rules.rx_mapping_indices if d is RX else drive.rules.tx_mapping_indices
        if allowed and pdo not in allowed:
            return False
        if is_mapping(pdo) is not d:
            return False
        return (pdo, 0) in drive.objects.entries or any(p.index == pdo for p in drive.device.pdos(d))

    def _pdo_entries(self, d: Direction, pdo: int) -> list[PdoEntry] | None:
        drive = self.drive
        if (pdo, 0) in drive.objects.entries:
            n = drive._read_int(pdo, 0) or 0
            return [PdoEntry.from_mapping_value(drive._read_int(pdo, s) or 0) for s in range(1, n + 1)]
        found = [p for p in drive.device.pdos(d) if p.index == pdo]
        for p in sorted(found, key=drive.device.esc_registers):  # a real PDO before ESC registers of its index
            return list(p.entries)
        return None
