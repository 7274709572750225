"""PDO configuration objects: what the drive accepts in the mapping objects (1600h-17FFh, 1A00h-1BFFh) and
the assignment objects (1C12h/1C13h) per its family rules, and the abort code it answers otherwise."""

from __future__ import annotations

from ecattool import abort as A
from ecattool.esi.model import Direction, PdoEntry
from ecattool.od.model import EcState
from ecattool.od.types import lookup
from ecattool.sim.drive.core import RX, TX, DriveCore, sdo_abort


def is_mapping(index: int) -> Direction | None:
    if 0x1600 <= index <= 0x17FF:
        return RX
    if 0x1A00 <= index <= 0x1BFF:
        return TX
    return None


_ASSIGN = {0x1C12: RX, 0x1C13: TX}


def is_assign(index: int) -> Direction | None:
    return _ASSIGN.get(index)


class PdoConfig(DriveCore):
    """The SDO side of the PDO configuration: defaults at power-on, mapping and assignment writes."""

    def _known_pdo_entries(self) -> dict[Direction, set[tuple[int, int, int]]]:
        """The entries the slave maps whatever the dictionary's flags say: those of the ESI's PDO list, and those
        of its dictionary's own default mapping that name an object of the dictionary at its size (a vendor ESI
        often leaves PdoMapping off objects its firmware maps by default: Synapticon's 607Ah). A default entry
        of a data type index (a dummy) or of an object that does not exist is not known: it is checked, and
        refused, as any written entry is."""
        known: dict[Direction, set[tuple[int, int, int]]] = {RX: set(), TX: set()}
        od = self.device.dictionary
        for d in (RX, TX):
            for pdo in self.device.pdos(d):
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
        if not (0x1600 <= index <= 0x17FF or 0x1A00 <= index <= 0x1BFF):
            return False
        count = self._entries.get((index, 0))
        if count is None or not count.default:
            return False
        n = int.from_bytes(count.default, "little")
        return all((e := self._entries.get((index, s))) is not None and bool(e.default) for s in range(1, n + 1))

    def _pdo_defaults(self) -> None:
        """Mapping objects hold the dictionary's own defaults where it gives them (:meth:`_own_mapping`), else the
        device's PDO entries; 1C12h/1C13h its default assignment (PDO@Sm)."""
        for d in (RX, TX):
            pdos = self.device.pdos(d)
            for pdo in pdos:
                if self.device.esc_registers(pdo) or (pdo.index, 0) not in self._entries or self._own_mapping(pdo.index):
                    continue
                for i, e in enumerate(pdo.entries, start=1):
                    if (pdo.index, i) in self._entries:
                        self._store[(pdo.index, i)] = e.mapping_value.to_bytes(4, "little")
                self._put(pdo.index, 0, len(pdo.entries))
            assign = d.assign_index
            if (assign, 0) in self._entries and any(p.sm is not None and not self.device.esc_registers(p) for p in pdos):
                chosen = [p.index for p in pdos if p.sm is not None and not self.device.esc_registers(p)]
                subs = sorted(s for (i, s) in self._entries if i == assign and s > 0)
                for s in subs:
                    self._store[(assign, s)] = b"\x00\x00"
                for s, index in zip(subs, chosen):
                    self._store[(assign, s)] = index.to_bytes(2, "little")
                self._put(assign, 0, min(len(chosen), len(subs)))

    def _assigned(self, d: Direction) -> list[int]:
        assign = d.assign_index
        if (assign, 0) not in self._entries:  # a virtual PDO is ESC registers: the slave assigns no such PDO
            return [p.index for p in self.device.pdos(d) if p.sm is not None and not self.device.esc_registers(p)]
        n = self._read_int(assign, 0) or 0
        chosen = (self._read_int(assign, s) or 0 for s in range(1, n + 1) if (assign, s) in self._entries)
        return [p for p in chosen if p]  # a 0 entry assigns nothing (Technosoft §2.5 leaves sub 2 at 0)

    def _mapping_write(self, d: Direction, index: int, sub: int, value: int) -> None:
        if not self.rules.mapping_writable or index in self._fixed:
            raise sdo_abort(index, sub, A.READ_ONLY)
        if self.esm is not EcState.PREOP:
            raise sdo_abort(index, sub, A.DATA_CANNOT_BE_STORED_STATE)
        if self.behaviour.mapping_assigned is not None and index in self._assigned(d):
            raise sdo_abort(index, sub, self.behaviour.mapping_assigned)
        if sub == 0:
            self._check_mapping_count(d, index, value)
            return
        if self.rules.mapping_write_needs_sub0_zero and self._read_int(index, 0):
            raise sdo_abort(index, sub, self.behaviour.mapping_busy)
        if value:
            self._mapping_entry_bits(d, index, sub, value)

    def _mapping_entry_bits(self, d: Direction, index: int, sub: int, value: int) -> int:
        """Check one mapping entry value; returns its bit length or raises the drive's abort."""
        idx, s, bits = value >> 16, (value >> 8) & 0xFF, value & 0xFF
        if bits == 0:
            raise sdo_abort(index, sub, A.NOT_MAPPABLE)
        if idx == 0:
            if not self.rules.gaps_allowed:
                raise sdo_abort(index, sub, A.NOT_MAPPABLE)
            return bits
        if idx in self.rules.dummy_indices or (idx < 0x20 and (idx, s) not in self._entries):
            allowed = self.rules.dummies_in_rx if d is RX else self.rules.dummies_in_tx
            if idx not in self.rules.dummy_indices or not allowed:
                raise sdo_abort(index, sub, A.NOT_MAPPABLE if idx in self.rules.dummy_indices else A.OBJECT_DOES_NOT_EXIST)
            e = self._entries.get((idx, s))
            dt = lookup(idx) if idx < 0x20 else None
            size = e.bit_size if e is not None else (dt.bits if dt is not None else None)
            if size is not None and size != bits:
                raise sdo_abort(index, sub, A.NOT_MAPPABLE)
            return bits
        if (idx, s, bits) in self._pdo_known[d]:
            return bits
        e = self._entries.get((idx, s))
        if e is None:
            raise sdo_abort(index, sub, A.OBJECT_DOES_NOT_EXIST)
        if not (e.rx_mappable if d is RX else e.tx_mappable) or e.bit_size != bits:
            raise sdo_abort(index, sub, A.NOT_MAPPABLE)
        return bits

    def _check_mapping_count(self, d: Direction, index: int, n: int) -> None:
        if n == 0:
            return
        subs = [s for s in range(1, n + 1)]
        if any((index, s) not in self._entries for s in subs):
            raise sdo_abort(index, 0, A.VALUE_TOO_HIGH)
        if self.rules.max_pdo_entries is not None and n > self.rules.max_pdo_entries:
            raise sdo_abort(index, 0, A.PDO_LENGTH_EXCEEDED)
        if not self.rules.mapping_write_needs_sub0_zero:
            return  # entries may follow sub-index 0 (Control Techniques 5.1.3); SAFE-OP checks the result
        total = 0
        for s in subs:
            v = self._read_int(index, s) or 0
            if not v:
                raise sdo_abort(index, 0, A.GENERAL_PARAMETER_INCOMPATIBILITY)
            total += self._mapping_entry_bits(d, index, 0, v)
        limit = self.rules.max_pdo_bits
        if limit is not None and total > limit and self.strict_pdo_length:
            raise sdo_abort(index, 0, A.PDO_LENGTH_EXCEEDED)

    def _assign_write(self, d: Direction, index: int, sub: int, value: int) -> None:
        if not self.rules.assign_writable:
            raise sdo_abort(index, sub, A.READ_ONLY)
        if self.esm is not EcState.PREOP:
            raise sdo_abort(index, sub, A.DATA_CANNOT_BE_STORED_STATE)
        if sub == 0:
            if value == 0:
                return
            limit = self.rules.max_assigned_rx if d is RX else self.rules.max_assigned_tx
            if limit is not None and value > limit:
                raise sdo_abort(index, 0, A.VALUE_TOO_HIGH)
            chosen = [self._read_int(index, s) or 0 for s in range(1, value + 1) if (index, s) in self._entries]
            if len(chosen) != value:
                raise sdo_abort(index, 0, A.VALUE_TOO_HIGH)
            chosen = [p for p in chosen if p]
            if any(not self._valid_pdo_index(d, p) for p in chosen) or len(set(chosen)) != len(chosen):
                raise sdo_abort(index, 0, A.INVALID_VALUE)
            if self._slow_in_first(d, chosen):
                raise sdo_abort(index, 0, A.GENERAL_PARAMETER_INCOMPATIBILITY)
            return
        if self.rules.assign_write_needs_sub0_zero and self._read_int(index, 0):
            raise sdo_abort(index, sub, self.behaviour.assign_busy)
        if value and not self._valid_pdo_index(d, value):
            raise sdo_abort(index, sub, A.INVALID_VALUE)

    def _slow_in_first(self, d: Direction, chosen: list[int]) -> bool:
        """Control Techniques 6.1.1: with two PDOs in a sync manager, slow parameters (SM-Applications,
        Inter-Option) may only be in the second (low priority) one; in the first the drive aborts."""
        if not self.rules.priority_rule or len(chosen) < 2:
            return False
        slow = self.rules.slow_indices
        return any(e.index in slow for e in self._pdo_entries(d, chosen[0]) or [])

    def _valid_pdo_index(self, d: Direction, pdo: int) -> bool:
        allowed = self.rules.rx_mapping_indices if d is RX else self.rules.tx_mapping_indices
        if allowed and pdo not in allowed:
            return False
        if is_mapping(pdo) is not d:
            return False
        return (pdo, 0) in self._entries or any(p.index == pdo for p in self.device.pdos(d))

    def _pdo_entries(self, d: Direction, pdo: int) -> list[PdoEntry] | None:
        if (pdo, 0) in self._entries:
            n = self._read_int(pdo, 0) or 0
            return [PdoEntry.from_mapping_value(self._read_int(pdo, s) or 0) for s in range(1, n + 1)]
        found = [p for p in self.device.pdos(d) if p.index == pdo]
        for p in sorted(found, key=self.device.esc_registers):  # a real PDO before ESC registers of its index
            return list(p.entries)
        return None
