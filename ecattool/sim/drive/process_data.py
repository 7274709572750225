"""Process data: the SAFE-OP check of the assigned PDOs that yields the process image layout, and the cyclic
exchange of the output and input images."""

from __future__ import annotations

from typing import TYPE_CHECKING

from ecattool.abort import AlStatus
from ecattool.errors import SdoAbort, TargetError
from ecattool.esi.model import Direction
from ecattool.od.model import EcState
from ecattool.sim import eeprom as ee
from ecattool.sim.drive.core import RX, TX, Layout
from ecattool.sim.drive.pdo import PdoConfig

if TYPE_CHECKING:
    from ecattool.sim.drive.app import DriveApp

#: looked up once: every cycle asks (an enum member's lookup costs as much as the comparison's rest)
_OP, _SAFEOP = EcState.OP, EcState.SAFEOP


class ProcessData:
    """The process data part: the process image built from the assignment (through the :class:`PdoConfig` part)
    at PRE-OP -> SAFE-OP, exchanged each cycle."""

    __slots__ = ("drive", "pdo", "_quiet", "_axis", "_io_last")

    def __init__(self, drive: DriveApp, pdo: PdoConfig) -> None:
        self.drive = drive
        self.pdo = pdo
        #: a CiA-402 drive (the cycle steps its motion); an I/O slave's cycle is the latch and the input image
        self._axis = drive.has_cia402
        #: an I/O slave's last cycle in OP: (its outputs, the store and its count of changes after the cycle, the
        #: layouts' slots, its inputs). See :meth:`_io_cycle`.
        self._io_last: tuple[bytes, object, int, object, object, bytes] | None = None
        #: the last cycle in OP: (its outputs, the drive's state before and after it where the cycle changed
        #: nothing, else None, its inputs). See :meth:`_quiet_state`.
        self._quiet: tuple[bytes, tuple[object, ...] | None, bytes] | None = None

    def _mapping_is_fixed(self, assigned: list[int]) -> bool:
        """Whether the master cannot change what is assigned: no CoE mailbox, or only Fixed PDOs."""
        drive = self.drive
        mailbox = drive.device.mailbox
        return mailbox is None or mailbox.coe is None or all(p in drive._fixed for p in assigned)

    def check_sm(self, d: Direction) -> Layout:
        """The SAFE-OP check of one direction's assigned PDOs; returns the process image layout."""
        drive = self.drive
        code = AlStatus.INVALID_OUTPUT_CONFIG if d is RX else AlStatus.INVALID_INPUT_CONFIG
        layout = Layout()
        assigned = self.pdo._assigned(d)
        per_sm: dict[int, int] = {}  # SM number -> bits of the PDOs it carries
        limit = drive.rules.max_assigned_rx if d is RX else drive.rules.max_assigned_tx
        if limit is not None and len(assigned) > limit:
            drive.state_machine.refuse(EcState.SAFEOP, code, f"{len(assigned)} PDOs assigned, at most {limit}")
        if self.pdo._slow_in_first(d, assigned):
            drive.state_machine.refuse(EcState.SAFEOP, code, "a slow parameter is mapped in the first (high priority) PDO")
        for pdo in assigned:
            entries = self.pdo._pdo_entries(d, pdo)
            if entries is None:
                drive.state_machine.refuse(EcState.SAFEOP, code, f"assigned PDO 0x{pdo:04X} does not exist")
            assert entries is not None
            bits = 0
            for e in entries:
                if e.index == 0 and e.bit_len == 0:
                    continue  # an empty gap some ESI PDO lists carry
                try:
                    self.pdo._mapping_entry_bits(d, pdo, 0, e.mapping_value)
                except SdoAbort:
                    drive.state_machine.refuse(EcState.SAFEOP, code, f"PDO 0x{pdo:04X} maps an invalid entry 0x{e.mapping_value:08X}")
                is_pad = e.index == 0 or e.index in drive.rules.dummy_indices or e.index < 0x20
                layout.entries.append((0 if is_pad else e.index, e.subindex, layout.bits + bits, e.bit_len))
                bits += e.bit_len
            if drive.rules.max_pdo_bits is not None and bits > drive.rules.max_pdo_bits:
                if drive.behaviour.pdo_length_emcy is not None:
                    drive.emcy(drive.behaviour.pdo_length_emcy)
                drive.state_machine.refuse(EcState.SAFEOP, code, f"PDO 0x{pdo:04X} is {bits} bits, at most {drive.rules.max_pdo_bits}")
            if drive.rules.max_pdo_entries is not None and len(entries) > drive.rules.max_pdo_entries:
                drive.state_machine.refuse(EcState.SAFEOP, code, f"PDO 0x{pdo:04X} has {len(entries)} entries")
            layout.bits += bits
            sm_no = self._sm_of(d, pdo)
            if sm_no is not None:
                per_sm[sm_no] = per_sm.get(sm_no, 0) + bits
        if layout.bits % 8 and not self._mapping_is_fixed(assigned):
            # a slave whose mapping the master cannot change (fixed PDOs, no CoE: an EL1002's 2 bits) has its
            # sync manager one byte long, the ESC pads the rest; a configurable one refuses the odd length
            drive.state_machine.refuse(EcState.SAFEOP, code, f"{layout.bits} bits of process data is not a whole number of bytes")
        for sm_no, bits in per_sm.items():
            sm = drive.device.sm(sm_no)
            size = (bits + 7) // 8
            if sm is not None and sm.max_size is not None and size > sm.max_size:
                drive.state_machine.refuse(EcState.SAFEOP, code, f"{size} bytes exceed SM{sm.number} maximum {sm.max_size}")
        return layout

    def _sm_of(self, d: Direction, pdo: int) -> int | None:
        """The sync manager that carries PDO ``pdo``: the one its ESI ``Sm`` names where that is a real sync manager
        of the direction (an EQ2339's outputs are over SM0 and SM1, one byte each), else the direction's first."""
        drive = self.drive
        kind = "Outputs" if d is RX else "Inputs"
        for p in drive.device.pdos(d):
            if p.index == pdo and not drive.device.esc_registers(p) and p.sm is not None:
                sm = drive.device.sm(p.sm)
                if sm is not None and sm.kind == kind and not sm.virtual:
                    return sm.number
        first = next((s for s in drive.device.sync_managers if s.kind == kind and not s.virtual), None)
        return first.number if first is not None else None

    def process_image_sizes(self) -> tuple[int, int]:
        """(output bytes, input bytes) of the current layout (valid from SAFE-OP on)."""
        drive = self.drive
        return drive.layout[RX].size, drive.layout[TX].size

    def exchange(self, outputs: bytes) -> bytes:
        """One cycle: in OP the outputs are written into the mapped objects and the motion advances one
        cycle; in SAFE-OP outputs are ignored. Returns the input image."""
        drive = self.drive
        esm = drive.esm
        if esm is not _OP and esm is not _SAFEOP:
            raise TargetError(f"no process data in {esm.value} (request SAFEOP or OP first)")
        rx = drive.layout[RX]
        if len(outputs) != rx.size:
            raise TargetError(f"output image is {len(outputs)} bytes, the drive expects {rx.size}")
        if esm is _OP and not self._axis:
            return self._io_cycle(rx, outputs)
        if esm is _OP:
            quiet = self._quiet
            if quiet is not None and quiet[0] == outputs:
                state = self._quiet_state()
                if state == quiet[1]:
                    return quiet[2]  # the cycle before this one, on the same outputs and state: a fixed point
            else:
                state = None
            # A drive latches the whole RxPDO image first and only then reacts to it (a new set-point in
            # the controlword must see the target position of the same cycle).
            outputs = bytes(outputs)  # a no-op for bytes: the store keeps bytes, never a caller's buffer
            self._latch(rx, outputs)
            drive.motion.step()
            inputs = self._pack_inputs()
            if state is None:
                self._quiet = (outputs, None, b"")  # a candidate: the next cycle compares its state
            else:
                after = self._quiet_state()
                self._quiet = (outputs, after, inputs) if after == state else (outputs, None, b"")
            return inputs
        self._quiet = None
        return self._pack_inputs()

    def _io_cycle(self, rx: Layout, outputs: bytes) -> bytes:
        """An I/O slave's cycle in OP: its process data is its objects as mapped, nothing is stepped: the outputs
        latched, the input image packed. The cycle is a function of the outputs, the store's values and the
        layouts alone, so when the outputs are those of the cycle before and the store has not changed since
        (the same store, the same count of changes) and the layouts are the same, its inputs are that cycle's
        (the latch would store nothing, the image would pack the same values)."""
        store = self.drive.objects.store
        tx_slots = self.drive.layout[TX].slots()
        last = self._io_last
        if last is not None and last[0] == outputs and last[1] is store and last[2] == store.changes \
                and last[3] is rx.slots() and last[4] is tx_slots:
            return last[5]
        outputs = bytes(outputs)  # the store keeps bytes, never a caller's buffer
        self._latch(rx, outputs)
        inputs = self._pack_inputs()
        self._io_last = (outputs, store, store.changes, rx.slots(), tx_slots, inputs)
        return inputs

    def _latch(self, rx: Layout, outputs: bytes) -> None:
        """The output image latched into the mapped objects that changed, then their reactions run (a drive
        latches the whole RxPDO image first and only then reacts to it)."""
        drive = self.drive
        image: int | None = None
        reactions: list[tuple[int, int, bytes]] = []
        stored = drive.objects.store.get
        try:
            for key, lo, hi, offset, bits in rx.slots():
                if lo >= 0:
                    raw = outputs[lo:hi]  # an entry on whole bytes: its bytes as they are
                else:
                    if image is None:
                        image = int.from_bytes(outputs, "little")
                    raw = ((image >> offset) & ((1 << bits) - 1)).to_bytes((bits + 7) // 8, "little")
                if stored(key) == raw:
                    continue  # unchanged: nothing to store and nothing to react to
                if self._pdo_write(key, raw):
                    reactions.append((key[0], key[1], raw))
        except ee.PowerLost:
            # the drive drops off the bus; it comes back in INIT with the EEPROM as far as it was written
            drive.nonvolatile.power_loss()
            raise TargetError("the drive lost power during an EEPROM write (it is back in INIT)") from None
        for index, sub, raw in reactions:
            drive._after_write[index](sub, int.from_bytes(raw, "little"))

    def _quiet_state(self) -> tuple[object, ...]:
        """Everything a cycle in OP reads besides its outputs, compared by value, and what it reports through:
        the store (which object, and its count of changes), the CiA-402 model (its every attribute; a profile
        move in progress keeps its own state, so none may be running), the unit conversions, the dictionary,
        the layouts, the flags and settings the motion step reads, and the counts of events and emergencies.

        Why skipping a cycle is exact: the cycle is a function of this state and the outputs (no clock, no
        random numbers). When a cycle on outputs O leaves the state exactly as it found it (and logs and
        reports nothing), the next cycle on the same O from the same state does the same: nothing, with the
        same inputs. So :meth:`exchange` returns the inputs of the cycle before where the outputs and this
        state are equal to that cycle's (tests/sim/test_sim_quiet_cycle.py runs both ways and compares)."""
        drive = self.drive
        cia = drive.cia
        layout = drive.layout
        rx, tx = layout[RX], layout[TX]
        store = drive.objects.store
        entries = drive.objects.entries
        log = drive.event_log
        plant = drive.plant
        # the parts' state read directly (attributes, no properties or per-part calls: every quiet cycle builds
        # this); the CiA-402 model's attributes as a copy of its __dict__, compared by value as a tuple of them was
        return (store, store.changes, cia, None if cia.move is None else object(), cia.__dict__.copy(),
                *drive.motion.modes_snapshot(),
                drive.units, entries, len(entries), rx, tx, tuple(rx.entries), tuple(tx.entries), rx.bits, tx.bits,
                drive.limit_active, drive.limit_switches, drive.homing_warning, drive.behaviour, drive.family,
                drive.homing_search_s, log.record_events, log.seq, len(log.emergencies),
                None if plant is None else plant.state(), drive.supervision.state())

    def _pdo_write(self, key: tuple[int, int], raw: bytes) -> bool:
        """Store one mapped output that changed (``key``: its index and sub-index); True when the object has a
        reaction to run once the image is latched."""
        drive = self.drive
        index = key[0]
        if index == 0x2065 or index == 0x2067:
            handler = drive._handlers_down.get(index)
            if handler is not None:
                try:
                    handler(key[1], raw, int.from_bytes(raw, "little"))
                except SdoAbort:
                    return False
        objects = drive.objects
        e = objects.entries.get(key)
        if e is not None and e.bit_size > 8 * len(raw):
            # a compact PDO maps the low bits of a larger object (EJ2521's 16-bit 7000h:12 of 32): they
            # replace the low bytes, the object keeps its high ones
            old = objects.store.get(key, b"")
            raw = raw + old[len(raw):(e.bit_size + 7) // 8].ljust((e.bit_size + 7) // 8 - len(raw), b"\x00")
        objects.store[key] = raw
        return index in drive._after_write

    def _pack_inputs(self) -> bytes:
        """The input image: each mapped object's value, cut or padded with zeros to its mapped length."""
        drive = self.drive
        tx = drive.layout[TX]
        stored = drive.objects.store.get
        whole = tx.pieces()
        if whole is not None:
            # on whole bytes: the values themselves, joined (a gap's key is in no store: its zeros)
            pieces, lengths = whole
            raws = [stored(key, zeros) for key, zeros in pieces]
            if tuple(map(len, raws)) != lengths:
                raws = [raw[:len(zeros)].ljust(len(zeros), b"\x00") for raw, (_, zeros) in zip(raws, pieces)]
            return b"".join(raws)
        image = 0
        for key, _, _, offset, bits in tx.slots():
            image |= (int.from_bytes(stored(key, b""), "little") & ((1 << bits) - 1)) << offset
        return image.to_bytes(tx.size, "little")
