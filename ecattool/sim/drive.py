"""The embedded drive simulator: an SDO server on bytes, the EtherCAT state machine, process data, CiA-402.

A :class:`Drive` is built from a :class:`~ecattool.esi.model.Device` (from an ESI or a built-in profile) and
the family's :class:`~ecattool.profiles.rules.FamilyRules`. It shares that *data* with the PDO checker but
makes its own decisions: every SDO is accepted or aborted with the code the drive sends, SAFE-OP is refused
with the AL status code the drive sets. It satisfies :class:`ecattool.target.base.SlaveTarget`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from fractions import Fraction
from pathlib import Path
from typing import Any

from ecattool.errors import SdoAbort, SdoTimeout, StateChangeError, TargetError
from ecattool.esi.model import Device, Direction, Identity, PdoEntry
from ecattool import abort as A
from ecattool.od.model import MAILBOX_STATES, EcState, Entry, ObjectCode
from ecattool.od.types import Kind, lookup
from ecattool.profiles.rules import FamilyRules, interpolation_period_ns
from ecattool.sim import eeprom as ee
from ecattool.sim import halt_homing as hh
from ecattool.sim.cia402 import CSP, HOMING, PP, Cia402, Homing, State
from ecattool.sim.faults import Faults
from ecattool.sim.units import Units, to_int, units_for

RX, TX = Direction.RX, Direction.TX

#: allowed ESM transitions (ETG.1000.6; Technosoft §3.1.1 derived matrix, HDT §3.02)
TRANSITIONS: dict[EcState, frozenset[EcState]] = {
    EcState.INIT: frozenset({EcState.PREOP, EcState.BOOT}),
    EcState.PREOP: frozenset({EcState.INIT, EcState.SAFEOP}),
    EcState.SAFEOP: frozenset({EcState.INIT, EcState.PREOP, EcState.OP}),
    EcState.OP: frozenset({EcState.INIT, EcState.PREOP, EcState.SAFEOP}),
    EcState.BOOT: frozenset({EcState.INIT}),
}

AL_INVALID_STATE_CHANGE = 0x0011
AL_BOOTSTRAP_NOT_SUPPORTED = 0x0013
AL_INVALID_OUTPUT_CONFIG = 0x001D
AL_INVALID_INPUT_CONFIG = 0x001E
AL_DC_INVALID_SYNC = 0x0030
AL_DC_INVALID_CYCLE = 0x0035


class FoeError(TargetError):
    """An FoE write was refused; ``code`` is the FoE error code (ETG.1000.6, 0x8000…)."""

    def __init__(self, name: str, code: int, reason: str) -> None:
        self.name = name
        self.code = code
        super().__init__(f"FoE write of {name!r} refused with error 0x{code:04X}: {reason}")


@dataclass(frozen=True, slots=True)
class Event:
    """One thing the drive did. ``kind``: sdo_upload, sdo_download, sdo_abort, sdo_timeout, state,
    state_refused, cia402, emcy, reset, power_loss, eeprom, foe, halt, homing."""

    seq: int
    kind: str
    data: dict[str, Any]


@dataclass(frozen=True, slots=True)
class Emergency:
    code: int
    register: int
    data: bytes = b"\x00" * 5

    def to_bytes(self) -> bytes:
        """The 8-byte EMCY message: code (LE), error register, 5 manufacturer bytes."""
        return self.code.to_bytes(2, "little") + bytes([self.register & 0xFF]) + self.data[:5].ljust(5, b"\x00")


@dataclass(frozen=True, slots=True)
class Behaviour:
    """How a family reacts where the manuals leave a choice (see docs/decisions.md, "Simulator")."""

    #: mapping entry (16xx/1Axx sub n) written while the mapping's sub-index 0 is not 0
    mapping_busy: int = A.SUBINDEX_CANNOT_BE_WRITTEN_SI0_NONZERO
    #: assignment entry (1C12/1C13 sub n) written while sub-index 0 is not 0
    assign_busy: int = A.SUBINDEX_CANNOT_BE_WRITTEN_SI0_NONZERO
    #: any write to a mapping object whose PDO is assigned (None: allowed in PRE-OP; the Control Techniques
    #: quick start rewrites 1A05h while the default 1C13h assigns it, ambiguity A4b)
    mapping_assigned: int | None = A.DATA_CANNOT_BE_STORED_STATE
    #: CiA-402 Shutdown only leaves SWITCH ON DISABLED in OP (Control Techniques 7.3.1)
    enable_needs_op: bool = False
    #: 6060h cannot change in OPERATION ENABLED / QUICK STOP ACTIVE (Control Techniques 7.3.6)
    mode_locked_when_enabled: bool = False
    #: an unsupported mode is accepted and reported with this EMCY (Technosoft 0xFF04) instead of an abort
    unsupported_mode_emcy: int | None = None
    #: 6061h follows 6060h only once OPERATION ENABLED is reached (Technosoft §4.2.3)
    mode_display_on_enable: bool = False
    #: EMCY sent when an over-long PDO is found at PRE-OP -> SAFE-OP (Technosoft 0x8220)
    pdo_length_emcy: int | None = None
    #: controlword bit 4 1 -> 0 stops a homing search (HDT §4.08.1 "1->0 stop"; CT/CiA-402 "1 = start or
    #: continue"); Technosoft only reacts to the 0 -> 1 edge (§6.3.1)
    homing_stop_on_bit4_clear: bool = True
    #: homing on the current position (35) also outside OPERATION ENABLED (Control Techniques 7.7.1, CiA-402)
    homing_current_outside_enabled: bool = False
    #: EMCY when a homing search fails (HDT FF02h, alarm FA_14 = bit 13 of the alarm bitmap) and its data
    homing_error_emcy: int | None = None
    homing_error_emcy_data: bytes = b""
    #: EMCY when a homing start names a method the drive does not have (Technosoft FF03h)
    homing_unavailable_emcy: int | None = None
    #: 6064h = sensor position + 607Ch at all times (HDT §4.06.6), not only when homing ends
    home_offset_continuous: bool = False
    #: a homing start while a search runs is ignored with statusword bit 7 (warning) set (Technosoft §4.2.2)
    homing_busy_warning: bool = False


BEHAVIOURS: dict[str, Behaviour] = {
    "technosoft-ipos": Behaviour(
        mapping_busy=A.DATA_CANNOT_BE_STORED_STATE, assign_busy=A.DATA_CANNOT_BE_STORED_STATE,
        unsupported_mode_emcy=0xFF04, mode_display_on_enable=True, pdo_length_emcy=0x8220,
        homing_stop_on_bit4_clear=False, homing_unavailable_emcy=0xFF03, homing_busy_warning=True,
    ),
    "hdt": Behaviour(homing_error_emcy=0xFF02, homing_error_emcy_data=(1 << 13).to_bytes(4, "little") + b"\x00",
                     home_offset_continuous=True),
    "controltechniques": Behaviour(enable_needs_op=True, mode_locked_when_enabled=True, mapping_assigned=None,
                                   homing_current_outside_enabled=True),
    "generic": Behaviour(homing_current_outside_enabled=True),
}

#: Control Techniques trip number -> 603Fh error code (SM-EtherCAT Table 9.17)
CT_TRIP_CODES = {0: 0x0000, 1: 0x3200, 3: 0x2300, 6: 0x9000, 30: 0x7510, 31: 0x5530, 33: 0x7200, 38: 0x6200,
                 106: 0x3210, 199: 0x6320, 202: 0x5000}


def _rules_for(device: Device) -> FamilyRules:
    try:
        from ecattool.profiles import rules_for
    except ImportError:
        return FamilyRules("generic", vendor_id=device.vendor_id)
    return rules_for(device)


def _complete(device: Device) -> Device:
    try:
        from ecattool.profiles import complete_generic
    except ImportError:
        return device
    return complete_generic(device)


def _decode_int(e: Entry | None, raw: bytes) -> int:
    """An integer entry's value from its bytes (the entry's bit size wins over a disagreeing type name)."""
    v = int.from_bytes(raw, "little")
    if e is None or e.datatype is None:
        return v
    bits = e.bit_size or 8 * len(raw)
    v &= (1 << bits) - 1
    if e.datatype.kind is Kind.SIGNED and v >= 1 << (bits - 1):
        v -= 1 << bits
    return v


def expand_default_modules(device: Device) -> Device:
    """A modular device (ETG.2001 slots) with each slot's default module plugged in: the module PDOs are
    added with the slot's PDO increment, their entries (and the module dictionaries) with the slot's index
    increment, as an ESI-configured master does before it starts the slave."""
    if not device.slots or device.rx_pdos or device.tx_pdos:
        return device
    import copy

    out = copy.deepcopy(device)
    by_ident = {m.ident: m for m in out.modules if m.ident is not None}
    for k, slot in enumerate(out.slots):
        module = by_ident.get(slot.default_module) if slot.default_module is not None else None
        if module is None:
            continue
        for _ in range(max(1, slot.min_instances)):
            idx_inc = (slot.slot_index_increment or 0) * k
            pdo_inc = (slot.slot_pdo_increment or 0) * k
            for obj in module.dictionary:
                moved = copy.deepcopy(obj)
                if 0x6000 <= obj.index <= 0x9FFF:
                    moved.index += idx_inc
                out.dictionary.add(moved)
            for src, dst in ((module.rx_pdos, out.rx_pdos), (module.tx_pdos, out.tx_pdos)):
                for pdo in src:
                    p = copy.deepcopy(pdo)
                    if p.depend_on_slot:
                        p.index += pdo_inc
                        for e in p.entries:
                            if e.index >= 0x2000:
                                e.index += idx_inc
                    dst.append(p)
            break
    return out


def _abort(index: int, sub: int, code: int) -> SdoAbort:
    return SdoAbort(index, sub, code)


def _is_mapping(index: int) -> Direction | None:
    if 0x1600 <= index <= 0x17FF:
        return RX
    if 0x1A00 <= index <= 0x1BFF:
        return TX
    return None


_ASSIGN = {0x1C12: RX, 0x1C13: TX}


def _is_assign(index: int) -> Direction | None:
    return _ASSIGN.get(index)


@dataclass
class _Layout:
    bits: int = 0
    #: (index, subindex, bit offset, bit length); index 0 = gap or dummy
    entries: list[tuple[int, int, int, int]] = field(default_factory=list)

    @property
    def size(self) -> int:
        return (self.bits + 7) // 8


class Drive:
    """A simulated EtherCAT CoE slave (a servo drive when its dictionary has the CiA-402 objects)."""

    #: seconds a homing method searches for its switch or index pulse before it reports a homing error
    #: (the simulated axis has none connected; docs/decisions.md)
    homing_search_s = Fraction(1)

    def __init__(self, device: Device, rules: FamilyRules | None = None, *, position: int = 0,
                 strict_pdo_length: bool = True, record_events: bool = True) -> None:
        self.device = device
        self.rules = rules if rules is not None else _rules_for(device)
        self.family = self.rules.family if self.rules.family in BEHAVIOURS else "generic"
        self.behaviour = BEHAVIOURS[self.family]
        self.position = position
        self.strict_pdo_length = strict_pdo_length
        self.record_events = record_events
        self.faults = Faults()
        self.events: list[Event] = []
        self.emergencies: list[Emergency] = []
        self.memory = ee.Memory()
        self._seq = 0
        self._pdo_known = self._known_pdo_entries()
        self._fixed = {p.index for p in (*device.rx_pdos, *device.tx_pdos) if p.fixed}
        self._pdo_only_set = frozenset(getattr(self.rules, "pdo_only_indices", ()))
        self._read_only_set = frozenset(getattr(self.rules, "read_only_indices", ()))
        # a handler returns True to store the value, False to skip storing it, None when the drive does not reply
        self._handlers_down: dict[int, Callable[[int, bytes, int | None], bool | None]] = {}
        self._handlers_up: dict[int, Callable[[int], bytes]] = {}
        self._install_handlers()
        self._power_on()

    # ------------------------------------------------------------------------------------------
    # construction
    # ------------------------------------------------------------------------------------------
    @classmethod
    def from_device(cls, device: Device, rules: FamilyRules | None = None, **kw: Any) -> "Drive":
        """A drive of ``device``. ESI devices are completed first (synthesised 1018h, mapping and assignment
        objects, default modules), exactly as :meth:`from_esi` does; built-in profile devices are complete."""
        if not device.source.startswith("profile:"):
            device = _complete(expand_default_modules(device))
        return cls(device, rules, **kw)

    @classmethod
    def from_profile(cls, name: str, product: str | None = None, revision: str | int | None = None,
                     **kw: Any) -> "Drive":
        from ecattool import profiles

        device = profiles.load(name, product=product, revision=revision)
        return cls(device, profiles.rules_for(device), **kw)

    @classmethod
    def from_esi(cls, path: str | Path, selector: str | None = None, **kw: Any) -> "Drive":
        from ecattool import esi

        device = esi.load_device(path, selector)
        return cls(_complete(expand_default_modules(device)), **kw)

    # ------------------------------------------------------------------------------------------
    # power on / reset
    # ------------------------------------------------------------------------------------------
    def _known_pdo_entries(self) -> dict[Direction, set[tuple[int, int, int]]]:
        known: dict[Direction, set[tuple[int, int, int]]] = {RX: set(), TX: set()}
        for d in (RX, TX):
            for pdo in self.device.pdos(d):
                for e in pdo.entries:
                    if e.index:
                        known[d].add((e.index, e.subindex, e.bit_len))
        return known

    def _power_on(self) -> None:
        self.esm = EcState.INIT
        self._reset_application()

    def _reset_application(self) -> None:
        """Dictionary to defaults, PDO configuration from the device description, CiA-402 restarted."""
        d = self.device
        self._store: dict[tuple[int, int], bytes] = {}
        self._entries: dict[tuple[int, int], Entry] = {}
        for obj in d.dictionary:
            for e in obj.entries.values():
                self._entries[(obj.index, e.subindex)] = e
                self._store[(obj.index, e.subindex)] = self._default_bytes(e)
        for dset in self._pdo_known.values():
            for idx, sub, bits in dset:
                self._store.setdefault((idx, sub), b"\x00" * ((bits + 7) // 8))
        self._identity_defaults()
        self._encoder_resolution()
        self._pdo_defaults()
        self.memory.reset()
        self._sync_memory_objects()
        self.layout: dict[Direction, _Layout] = {RX: _Layout(), TX: _Layout()}
        self.cia = Cia402(enable_needs_op=self.behaviour.enable_needs_op)
        self.limit_active = False
        self.limit_switches = (False, False)  # (negative, positive) inputs, set_limit_switches()
        self.homing_warning = False  # Technosoft statusword bit 7 (homing start ignored)
        self.has_cia402 = (0x6040, 0) in self._entries and (0x6041, 0) in self._entries
        self.units: Units = units_for(self.family, self._read_int, revision=d.revision,
                                      has_210f=0x210F in d.dictionary, cycle_s=self.cycle_time())
        self._refresh_inputs()

    def _default_bytes(self, e: Entry) -> bytes:
        size = e.byte_size
        if e.default is not None:
            raw = e.default
            if e.datatype is not None and e.datatype.bits is None:
                return raw
            return raw[:size].ljust(size, b"\x00")
        return b"\x00" * size

    def _identity_defaults(self) -> None:
        ident = self.device.identity
        for sub, value in ((1, ident.vendor_id), (2, ident.product_code), (3, ident.revision), (4, ident.serial)):
            e = self._entries.get((0x1018, sub))
            if e is not None and e.default is None and e.byte_size == 4:
                self._store[(0x1018, sub)] = value.to_bytes(4, "little")

    def _encoder_resolution(self) -> None:
        """Control Techniques 608Fh is read-only and "read from the drive's encoder configuration" (A24):
        the drive reports its position resolution, 65536 increments per revolution (the drive's 1/2^16-turn
        position format), not the table default 1/1. :meth:`set_encoder_resolution` changes it."""
        if self.family == "controltechniques" and (0x608F, 1) in self._entries:
            self._put(0x608F, 1, self.rules.counts_per_rev or 65536)
            self._put(0x608F, 2, 1)

    def set_encoder_resolution(self, increments: int, revolutions: int = 1) -> None:
        """The drive's feedback configuration changes (what 608Fh reports; also writable where 608Fh is RW)."""
        self._put(0x608F, 1, increments)
        self._put(0x608F, 2, revolutions)

    def _pdo_defaults(self) -> None:
        """Mapping objects hold the device's PDO entries; 1C12h/1C13h its default assignment (PDO@Sm)."""
        for d in (RX, TX):
            pdos = self.device.pdos(d)
            for pdo in pdos:
                if (pdo.index, 0) not in self._entries:
                    continue
                for i, e in enumerate(pdo.entries, start=1):
                    if (pdo.index, i) in self._entries:
                        self._store[(pdo.index, i)] = e.mapping_value.to_bytes(4, "little")
                self._put(pdo.index, 0, len(pdo.entries))
            assign = d.assign_index
            if (assign, 0) in self._entries and any(p.sm is not None for p in pdos):
                chosen = [p.index for p in pdos if p.sm is not None]
                subs = sorted(s for (i, s) in self._entries if i == assign and s > 0)
                for s in subs:
                    self._store[(assign, s)] = b"\x00\x00"
                for s, index in zip(subs, chosen):
                    self._store[(assign, s)] = index.to_bytes(2, "little")
                self._put(assign, 0, min(len(chosen), len(subs)))

    def cycle_time(self) -> Fraction:
        """The process-data cycle in seconds: 60C2h (sub1 × 10^sub2) where present, else 1 ms."""
        if hasattr(self, "_store"):
            base, exp = self._read_int(0x60C2, 1), self._read_int(0x60C2, 2)
            if base and exp is not None and -9 <= exp <= 2:
                return interpolation_period_ns(base, exp) / 10**9
        return Fraction(1, 1000)

    # ------------------------------------------------------------------------------------------
    # helpers on the store
    # ------------------------------------------------------------------------------------------
    def _read_int(self, index: int, sub: int) -> int | None:
        e = self._entries.get((index, sub))
        raw = self._store.get((index, sub))
        if raw is None:
            return None
        return _decode_int(e, raw)

    def _put(self, index: int, sub: int, value: int) -> None:
        e = self._entries.get((index, sub))
        if e is None:
            return
        size = e.byte_size
        signed = e.datatype is not None and e.datatype.kind is Kind.SIGNED
        mask = (1 << (8 * size)) - 1
        self._store[(index, sub)] = (value & mask).to_bytes(size, "little", signed=False) if signed else \
            (value & mask).to_bytes(size, "little")

    def value(self, index: int, sub: int = 0) -> Any:
        """The decoded value of an entry (no SDO rules, no side effects): for tests and inspection."""
        e = self._entries.get((index, sub))
        raw = self._store[(index, sub)]
        return e.decode(raw) if e is not None and e.datatype is not None else raw

    def _log(self, kind: str, **data: Any) -> None:
        if self.record_events:
            self._seq += 1
            self.events.append(Event(self._seq, kind, data))

    def emcy(self, code: int, data: bytes = b"") -> Emergency:
        """Send an emergency message (and log it). Also sets 603Fh/1001h where the drive has them."""
        register = self._read_int(0x1001, 0) or 0
        if code:
            register |= 0x01
            register |= {0x2: 0x02, 0x3: 0x04, 0x4: 0x08, 0x8: 0x10}.get(code >> 12, 0)
            self._put(0x1001, 0, register)
        if code and (0x1003, 1) in self._entries:
            self._push_error_history(code)
        m = Emergency(code, register, bytes(data))
        self.emergencies.append(m)
        self._log("emcy", code=code, register=register, data=bytes(data).hex())
        return m

    def _push_error_history(self, code: int) -> None:
        """1003h: newest error in sub-index 1, older ones shifted down, sub-index 0 = count (CiA-301)."""
        subs = sorted(s for (i, s) in self._entries if i == 0x1003 and s > 0)
        for s in reversed(subs[1:]):
            self._store[(0x1003, s)] = self._store[(0x1003, s - 1)]
        self._put(0x1003, 1, code)
        self._put(0x1003, 0, min(len(subs), (self._read_int(0x1003, 0) or 0) + 1))

    # ------------------------------------------------------------------------------------------
    # SlaveTarget
    # ------------------------------------------------------------------------------------------
    def identity(self) -> Identity:
        return self.device.identity

    def state(self) -> EcState:
        return self.esm

    def sdo_upload(self, index: int, subindex: int, complete_access: bool = False) -> bytes:
        planned = self.faults.next_sdo()
        if self.esm not in MAILBOX_STATES:
            self._log("sdo_timeout", index=index, subindex=subindex, reason=f"no mailbox in {self.esm.value}")
            raise SdoTimeout(index, subindex)
        if planned is not None:
            self._planned(planned, index, subindex)
        try:
            data = self._ca_upload(index, subindex) if complete_access else self._upload(index, subindex)
        except SdoAbort as exc:
            self._log("sdo_abort", op="upload", index=index, subindex=subindex, code=exc.code)
            raise
        if planned is not None and planned[0] == "drop":
            self._log("sdo_timeout", index=index, subindex=subindex, reason="reply dropped (fault injection)")
            raise SdoTimeout(index, subindex)
        self._log("sdo_upload", index=index, subindex=subindex, data=data.hex())
        return data

    def sdo_download(self, index: int, subindex: int, data: bytes, complete_access: bool = False,
                     expect_reply: bool = True) -> None:
        planned = self.faults.next_sdo()
        if self.esm not in MAILBOX_STATES:
            self._log("sdo_timeout", index=index, subindex=subindex, reason=f"no mailbox in {self.esm.value}")
            raise SdoTimeout(index, subindex)
        if planned is not None:
            if planned[0] == "drop" and not planned[1]:
                self._log("sdo_timeout", index=index, subindex=subindex, reason="request lost (fault injection)")
                raise SdoTimeout(index, subindex)
            self._planned(planned, index, subindex)
        data = bytes(data)
        try:
            if complete_access:
                self._ca_download(index, subindex, data)
                no_reply = False
            else:
                no_reply = self._download(index, subindex, data)
        except SdoAbort as exc:
            self._log("sdo_abort", op="download", index=index, subindex=subindex, data=data.hex(), code=exc.code)
            raise
        except ee.PowerLost:
            self._power_loss()
            raise SdoTimeout(index, subindex) from None
        self._log("sdo_download", index=index, subindex=subindex, data=data.hex())
        if no_reply or (planned is not None and planned[0] == "drop"):
            if expect_reply:
                self._log("sdo_timeout", index=index, subindex=subindex, reason="the drive sends no reply")
                raise SdoTimeout(index, subindex)

    def _planned(self, planned: tuple[str, int], index: int, subindex: int) -> None:
        if planned[0] == "abort":
            self._log("sdo_abort", op="injected", index=index, subindex=subindex, code=planned[1])
            raise _abort(index, subindex, planned[1])

    # ------------------------------------------------------------------------------------------
    # SDO upload
    # ------------------------------------------------------------------------------------------
    def _entry(self, index: int, sub: int) -> Entry:
        e = self._entries.get((index, sub))
        if e is None:
            if index not in self.device.dictionary:
                raise _abort(index, sub, A.OBJECT_DOES_NOT_EXIST)
            raise _abort(index, sub, A.SUBINDEX_DOES_NOT_EXIST)
        return e

    def _pdo_only(self, index: int, sub: int) -> None:
        if index in self._pdo_only_set:
            raise _abort(index, sub, A.UNSUPPORTED_ACCESS)  # Control Techniques 8.5: 2830h/2831h cyclic only

    def _upload(self, index: int, sub: int) -> bytes:
        e = self._entry(index, sub)
        self._pdo_only(index, sub)
        if not e.access.read:
            raise _abort(index, sub, A.WRITE_ONLY)
        if self.esm not in e.access.read:
            raise _abort(index, sub, A.DATA_CANNOT_BE_STORED_STATE)
        handler = self._handlers_up.get(index)
        if handler is not None:
            return handler(sub)
        return self._store[(index, sub)]

    def _ca_supported(self, index: int, sub: int) -> None:
        mb = self.device.mailbox
        if mb is None or mb.coe is None or not mb.coe.complete_access:
            raise _abort(index, sub, A.COMPLETE_ACCESS_NOT_SUPPORTED)
        obj = self.device.dictionary.get(index)
        if obj is None:
            raise _abort(index, sub, A.OBJECT_DOES_NOT_EXIST)
        if obj.object_code is ObjectCode.VAR or sub > 1:
            raise _abort(index, sub, A.UNSUPPORTED_ACCESS)

    def _ca_subs(self, index: int, first: int) -> list[int]:
        return sorted(s for (i, s) in self._entries if i == index and s >= first)

    def _ca_upload(self, index: int, sub: int) -> bytes:
        """Complete access: sub-index 0 padded to 16 bits, then every entry bit-packed (ETG.1000.6)."""
        self._ca_supported(index, sub)
        acc = 0
        nbits = 0
        for s in self._ca_subs(index, sub):
            raw = self._upload(index, s)
            e = self._entries[(index, s)]
            bits = 16 if s == 0 else (e.bit_size or 8 * len(raw))
            acc |= (int.from_bytes(raw, "little") & ((1 << bits) - 1)) << nbits
            nbits += bits
        return acc.to_bytes((nbits + 7) // 8, "little")

    # ------------------------------------------------------------------------------------------
    # SDO download
    # ------------------------------------------------------------------------------------------
    def _download(self, index: int, sub: int, data: bytes) -> bool:
        """Check and apply one download; returns True when the drive sends no reply (2080h reset)."""
        e = self._entry(index, sub)
        self._pdo_only(index, sub)
        if not e.access.write or (sub and index in self._read_only_set):
            raise _abort(index, sub, A.READ_ONLY)
        if self.esm not in e.access.write:
            raise _abort(index, sub, A.DATA_CANNOT_BE_STORED_STATE)
        size = e.byte_size
        dt = e.datatype
        variable = dt is not None and dt.bits is None
        if variable:
            if size and len(data) > size:
                raise _abort(index, sub, A.LENGTH_TOO_HIGH)
        elif len(data) != size:
            raise _abort(index, sub, A.LENGTH_TOO_HIGH if len(data) > size else A.LENGTH_TOO_LOW)
        value: int | None = None
        if dt is not None and dt.kind in (Kind.SIGNED, Kind.UNSIGNED, Kind.BITS, Kind.BOOL):
            value = _decode_int(e, data)
            if e.minimum is not None and value < e.minimum:
                raise _abort(index, sub, A.VALUE_TOO_LOW)
            if e.maximum is not None and value > e.maximum:
                raise _abort(index, sub, A.VALUE_TOO_HIGH)
        elif dt is not None and dt.kind is Kind.REAL:
            f = dt.decode(data)
            if e.minimum is not None and f < e.minimum:
                raise _abort(index, sub, A.VALUE_TOO_LOW)
            if e.maximum is not None and f > e.maximum:
                raise _abort(index, sub, A.VALUE_TOO_HIGH)
        if variable and size:
            data = data.ljust(size, b"\x00")
        d = _is_mapping(index)
        if d is not None:
            self._mapping_write(d, index, sub, value if value is not None else 0)
        else:
            d = _is_assign(index)
            if d is not None:
                self._assign_write(d, index, sub, value if value is not None else 0)
        handler = self._handlers_down.get(index)
        if handler is not None:
            result = handler(sub, data, value)
            if result is None:
                return True  # no reply (reset)
            if not result:
                return False
        self._store[(index, sub)] = data
        if index in self._after_write:
            self._after_write[index](sub, value)
        return False

    def _ca_download(self, index: int, sub: int, data: bytes) -> None:
        """Complete access download: applied as the single writes a master would make, all or nothing."""
        self._ca_supported(index, sub)
        subs = self._ca_subs(index, sub)
        pos = 0
        writes: list[tuple[int, bytes]] = []
        for s in subs:
            e = self._entries[(index, s)]
            nbytes = 2 if s == 0 else max(1, e.byte_size)
            if pos + nbytes > len(data):
                break
            chunk = data[pos:pos + nbytes]
            writes.append((s, chunk[:1] if s == 0 else chunk))
            pos += nbytes
        if pos != len(data) or not writes:
            raise _abort(index, sub, A.LENGTH_MISMATCH if writes else A.LENGTH_TOO_LOW)
        snapshot = dict(self._store)
        try:
            if writes[0][0] == 0:
                count = writes[0][1]
                e0 = self._entries[(index, 0)]
                if e0.access.write:
                    self._download(index, 0, b"\x00")
                for s, chunk in writes[1:]:
                    if self._entries[(index, s)].access.write:
                        self._download(index, s, chunk)
                if e0.access.write:
                    self._download(index, 0, count)
            else:
                for s, chunk in writes:
                    self._download(index, s, chunk)
        except SdoAbort:
            self._store = snapshot
            raise

    # --- PDO configuration ---------------------------------------------------------------------
    def _assigned(self, d: Direction) -> list[int]:
        assign = d.assign_index
        if (assign, 0) not in self._entries:
            return [p.index for p in self.device.pdos(d) if p.sm is not None]
        n = self._read_int(assign, 0) or 0
        chosen = (self._read_int(assign, s) or 0 for s in range(1, n + 1) if (assign, s) in self._entries)
        return [p for p in chosen if p]  # a 0 entry assigns nothing (Technosoft §2.5 leaves sub 2 at 0)

    def _mapping_write(self, d: Direction, index: int, sub: int, value: int) -> None:
        if not self.rules.mapping_writable or index in self._fixed:
            raise _abort(index, sub, A.READ_ONLY)
        if self.esm is not EcState.PREOP:
            raise _abort(index, sub, A.DATA_CANNOT_BE_STORED_STATE)
        if self.behaviour.mapping_assigned is not None and index in self._assigned(d):
            raise _abort(index, sub, self.behaviour.mapping_assigned)
        if sub == 0:
            self._check_mapping_count(d, index, value)
            return
        if self.rules.mapping_write_needs_sub0_zero and self._read_int(index, 0):
            raise _abort(index, sub, self.behaviour.mapping_busy)
        if value:
            self._mapping_entry_bits(d, index, sub, value)

    def _mapping_entry_bits(self, d: Direction, index: int, sub: int, value: int) -> int:
        """Check one mapping entry value; returns its bit length or raises the drive's abort."""
        idx, s, bits = value >> 16, (value >> 8) & 0xFF, value & 0xFF
        if bits == 0:
            raise _abort(index, sub, A.NOT_MAPPABLE)
        if idx == 0:
            if not self.rules.gaps_allowed:
                raise _abort(index, sub, A.NOT_MAPPABLE)
            return bits
        if idx in self.rules.dummy_indices or (idx < 0x20 and (idx, s) not in self._entries):
            allowed = self.rules.dummies_in_rx if d is RX else self.rules.dummies_in_tx
            if idx not in self.rules.dummy_indices or not allowed:
                raise _abort(index, sub, A.NOT_MAPPABLE if idx in self.rules.dummy_indices else A.OBJECT_DOES_NOT_EXIST)
            e = self._entries.get((idx, s))
            dt = lookup(idx) if idx < 0x20 else None
            size = e.bit_size if e is not None else (dt.bits if dt is not None else None)
            if size is not None and size != bits:
                raise _abort(index, sub, A.NOT_MAPPABLE)
            return bits
        if (idx, s, bits) in self._pdo_known[d]:
            return bits
        e = self._entries.get((idx, s))
        if e is None:
            raise _abort(index, sub, A.OBJECT_DOES_NOT_EXIST)
        if not (e.rx_mappable if d is RX else e.tx_mappable) or e.bit_size != bits:
            raise _abort(index, sub, A.NOT_MAPPABLE)
        return bits

    def _check_mapping_count(self, d: Direction, index: int, n: int) -> None:
        if n == 0:
            return
        subs = [s for s in range(1, n + 1)]
        if any((index, s) not in self._entries for s in subs):
            raise _abort(index, 0, A.VALUE_TOO_HIGH)
        if self.rules.max_pdo_entries is not None and n > self.rules.max_pdo_entries:
            raise _abort(index, 0, A.PDO_LENGTH_EXCEEDED)
        if not self.rules.mapping_write_needs_sub0_zero:
            return  # entries may follow sub-index 0 (Control Techniques 5.1.3); SAFE-OP checks the result
        total = 0
        for s in subs:
            v = self._read_int(index, s) or 0
            if not v:
                raise _abort(index, 0, A.GENERAL_PARAMETER_INCOMPATIBILITY)
            total += self._mapping_entry_bits(d, index, 0, v)
        limit = self.rules.max_pdo_bits
        if limit is not None and total > limit and self.strict_pdo_length:
            raise _abort(index, 0, A.PDO_LENGTH_EXCEEDED)

    def _assign_write(self, d: Direction, index: int, sub: int, value: int) -> None:
        if not self.rules.assign_writable:
            raise _abort(index, sub, A.READ_ONLY)
        if self.esm is not EcState.PREOP:
            raise _abort(index, sub, A.DATA_CANNOT_BE_STORED_STATE)
        if sub == 0:
            if value == 0:
                return
            limit = self.rules.max_assigned_rx if d is RX else self.rules.max_assigned_tx
            if limit is not None and value > limit:
                raise _abort(index, 0, A.VALUE_TOO_HIGH)
            chosen = [self._read_int(index, s) or 0 for s in range(1, value + 1) if (index, s) in self._entries]
            if len(chosen) != value:
                raise _abort(index, 0, A.VALUE_TOO_HIGH)
            chosen = [p for p in chosen if p]
            if any(not self._valid_pdo_index(d, p) for p in chosen) or len(set(chosen)) != len(chosen):
                raise _abort(index, 0, A.INVALID_VALUE)
            if self._slow_in_first(d, chosen):
                raise _abort(index, 0, A.GENERAL_PARAMETER_INCOMPATIBILITY)
            return
        if self.rules.assign_write_needs_sub0_zero and self._read_int(index, 0):
            raise _abort(index, sub, self.behaviour.assign_busy)
        if value and not self._valid_pdo_index(d, value):
            raise _abort(index, sub, A.INVALID_VALUE)

    def _slow_in_first(self, d: Direction, chosen: list[int]) -> bool:
        """Control Techniques 6.1.1: with two PDOs in a sync manager, slow parameters (SM-Applications,
        Inter-Option) may only be in the second (low priority) one; in the first the drive aborts."""
        if not self.rules.priority_rule or len(chosen) < 2:
            return False
        slow: frozenset[int] = getattr(self.rules, "slow_indices", frozenset())
        return any(e.index in slow for e in self._pdo_entries(d, chosen[0]) or [])

    def _valid_pdo_index(self, d: Direction, pdo: int) -> bool:
        allowed = self.rules.rx_mapping_indices if d is RX else self.rules.tx_mapping_indices
        if allowed and pdo not in allowed:
            return False
        if _is_mapping(pdo) is not d:
            return False
        return (pdo, 0) in self._entries or any(p.index == pdo for p in self.device.pdos(d))

    # ------------------------------------------------------------------------------------------
    # EtherCAT state machine
    # ------------------------------------------------------------------------------------------
    def request_state(self, state: EcState) -> None:
        current = self.esm
        refusal = self.faults.state_refusal(state)
        if refusal is not None:
            self._refuse(state, refusal, "fault injection")
        if state is current:
            return
        if state not in TRANSITIONS[current]:
            self._refuse(state, AL_INVALID_STATE_CHANGE, "not an allowed transition")
        if state is EcState.BOOT and not (self.device.mailbox and "FoE" in self.device.mailbox.protocols):
            self._refuse(state, AL_BOOTSTRAP_NOT_SUPPORTED, "the device has no FoE bootstrap")
        if current is EcState.PREOP and state is EcState.SAFEOP:
            self.layout = {RX: self._check_sm(RX), TX: self._check_sm(TX)}
        if state is EcState.OP:
            self._check_dc()
        if current is EcState.OP and self.has_cia402:
            self._cia_moves(self.cia.communication_lost(), "ESM left OP")
        self.esm = state
        self._log("state", previous=current.value, state=state.value)
        self._esm_effects(current, state)
        self._refresh_inputs()

    #: Control Techniques Pr MM.04 (5.5, Table 5.6): the ESM state as the module reports it in its menu
    _CT_MM04 = {EcState.INIT: 1, EcState.PREOP: 2, EcState.SAFEOP: 4, EcState.OP: 8}
    #: Control Techniques 7.3.1: the module writes these drive parameters, in this order, on SAFE-OP -> OP
    #: (Pr 6.42 = 0, Pr 6.43 = 1: control word enable; Pr 3.22 = 0, Pr 3.23 = 1 where the drive has them)
    _CT_TO_OP = ((0x2006, 42, 0), (0x2006, 43, 1), (0x2003, 22, 0), (0x2003, 23, 1))

    def _esm_effects(self, previous: EcState, state: EcState) -> None:
        """What a family's module does itself on an ESM change (Control Techniques: MM.04 follows the state in
        the slot menu 0x200F and its mirror 0x203C; the SAFE-OP -> OP parameter writes)."""
        if self.family != "controltechniques":
            return
        code = self._CT_MM04.get(state)
        if code is not None:
            for menu in (0x200F, 0x203C):
                self._put(menu, 4, code)
        if previous is EcState.SAFEOP and state is EcState.OP:
            for index, sub, value in self._CT_TO_OP:
                if (index, sub) in self._entries:
                    self._put(index, sub, value)
                    self._log("drive_parameter", parameter=f"{index - 0x2000}.{sub:02d}", value=value,
                              reason="SAFE-OP -> OP (7.3.1)")

    def _refuse(self, state: EcState, code: int, why: str) -> None:
        self._log("state_refused", previous=self.esm.value, requested=state.value, al_status=code, reason=why)
        raise StateChangeError(state.value, self.esm.value, code)

    def _check_sm(self, d: Direction) -> _Layout:
        """The SAFE-OP check of one direction's assigned PDOs; returns the process image layout."""
        code = AL_INVALID_OUTPUT_CONFIG if d is RX else AL_INVALID_INPUT_CONFIG
        layout = _Layout()
        assigned = self._assigned(d)
        limit = self.rules.max_assigned_rx if d is RX else self.rules.max_assigned_tx
        if limit is not None and len(assigned) > limit:
            self._refuse(EcState.SAFEOP, code, f"{len(assigned)} PDOs assigned, at most {limit}")
        if self._slow_in_first(d, assigned):
            self._refuse(EcState.SAFEOP, code, "a slow parameter is mapped in the first (high priority) PDO")
        for pdo in assigned:
            entries = self._pdo_entries(d, pdo)
            if entries is None:
                self._refuse(EcState.SAFEOP, code, f"assigned PDO 0x{pdo:04X} does not exist")
            assert entries is not None
            bits = 0
            for e in entries:
                if e.index == 0 and e.bit_len == 0:
                    continue  # an empty gap some ESI PDO lists carry
                try:
                    self._mapping_entry_bits(d, pdo, 0, e.mapping_value)
                except SdoAbort:
                    self._refuse(EcState.SAFEOP, code, f"PDO 0x{pdo:04X} maps an invalid entry 0x{e.mapping_value:08X}")
                is_pad = e.index == 0 or e.index in self.rules.dummy_indices or e.index < 0x20
                layout.entries.append((0 if is_pad else e.index, e.subindex, layout.bits + bits, e.bit_len))
                bits += e.bit_len
            if self.rules.max_pdo_bits is not None and bits > self.rules.max_pdo_bits:
                if self.behaviour.pdo_length_emcy is not None:
                    self.emcy(self.behaviour.pdo_length_emcy)
                self._refuse(EcState.SAFEOP, code, f"PDO 0x{pdo:04X} is {bits} bits, at most {self.rules.max_pdo_bits}")
            if self.rules.max_pdo_entries is not None and len(entries) > self.rules.max_pdo_entries:
                self._refuse(EcState.SAFEOP, code, f"PDO 0x{pdo:04X} has {len(entries)} entries")
            layout.bits += bits
        if layout.bits % 8:
            self._refuse(EcState.SAFEOP, code, f"{layout.bits} bits of process data is not a whole number of bytes")
        sm = self.device.process_sm(d)
        if sm is not None and sm.max_size is not None and layout.size > sm.max_size:
            self._refuse(EcState.SAFEOP, code, f"{layout.size} bytes exceed SM{sm.number} maximum {sm.max_size}")
        return layout

    def _pdo_entries(self, d: Direction, pdo: int) -> list[PdoEntry] | None:
        if (pdo, 0) in self._entries:
            n = self._read_int(pdo, 0) or 0
            return [PdoEntry.from_mapping_value(self._read_int(pdo, s) or 0) for s in range(1, n + 1)]
        for p in self.device.pdos(d):
            if p.index == pdo:
                return list(p.entries)
        return None

    def process_image_sizes(self) -> tuple[int, int]:
        """(output bytes, input bytes) of the current layout (valid from SAFE-OP on)."""
        return self.layout[RX].size, self.layout[TX].size

    # ------------------------------------------------------------------------------------------
    # process data
    # ------------------------------------------------------------------------------------------
    def exchange(self, outputs: bytes) -> bytes:
        """One cycle: in OP the outputs are written into the mapped objects and the motion advances one
        cycle; in SAFE-OP outputs are ignored. Returns the input image."""
        if self.esm not in (EcState.SAFEOP, EcState.OP):
            raise TargetError(f"no process data in {self.esm.value} (request SAFEOP or OP first)")
        rx = self.layout[RX]
        if len(outputs) != rx.size:
            raise TargetError(f"output image is {len(outputs)} bytes, the drive expects {rx.size}")
        if self.esm is EcState.OP:
            # A drive latches the whole RxPDO image first and only then reacts to it (a new set-point in
            # the controlword must see the target position of the same cycle).
            image = int.from_bytes(outputs, "little")
            reactions: list[tuple[int, int, bytes]] = []
            try:
                for index, sub, offset, bits in rx.entries:
                    if index == 0:
                        continue
                    raw = ((image >> offset) & ((1 << bits) - 1)).to_bytes((bits + 7) // 8, "little")
                    if self._pdo_write(index, sub, raw):
                        reactions.append((index, sub, raw))
            except ee.PowerLost:
                # the drive drops off the bus; it comes back in INIT with the EEPROM as far as it was written
                self._power_loss()
                raise TargetError("the drive lost power during an EEPROM write (it is back in INIT)") from None
            for index, sub, raw in reactions:
                self._after_write[index](sub, int.from_bytes(raw, "little"))
            self.step()
        return self._pack_inputs()

    def _pdo_write(self, index: int, sub: int, raw: bytes) -> bool:
        """Store one mapped output; True when the object has a reaction to run once the image is latched."""
        old = self._store.get((index, sub))
        handler = self._handlers_down.get(index)
        if index in (0x2065, 0x2067) and handler is not None:
            if old == raw:
                return False
            try:
                handler(sub, raw, int.from_bytes(raw, "little"))
            except SdoAbort:
                return False
        self._store[(index, sub)] = raw
        return index in self._after_write and old != raw

    def _pack_inputs(self) -> bytes:
        tx = self.layout[TX]
        image = 0
        for index, sub, offset, bits in tx.entries:
            if index == 0:
                continue
            raw = self._store.get((index, sub), b"")
            image |= (int.from_bytes(raw, "little") & ((1 << bits) - 1)) << offset
        return image.to_bytes(tx.size, "little")

    # ------------------------------------------------------------------------------------------
    # CiA-402 and motion
    # ------------------------------------------------------------------------------------------
    def _cia_moves(self, moves: list[tuple[State, State]], why: str) -> None:
        for old, new in moves:
            self._log("cia402", previous=old.value, state=new.value, reason=why)
            if new is State.OPERATION_ENABLED and self.behaviour.mode_display_on_enable:
                self._put(0x6061, 0, self._read_int(0x6060, 0) or 0)

    def _on_controlword(self, sub: int, value: int | None) -> None:
        cw = value or 0
        prev = self.cia.controlword
        moves = self.cia.controlword_written(cw, ecat_op=self.esm is EcState.OP,
                                             quick_stop_option=self._read_int(0x605A, 0) or 2)
        self._cia_moves(moves, f"controlword 0x{cw:04X}")
        if self.cia.state is State.OPERATION_ENABLED and self.mode() == PP:
            if cw & 0x10 and not prev & 0x10:
                relative = bool(cw & 0x40)
                target = (self._read_int(0x607A, 0) or 0) - (0 if relative else self._home_offset())
                self.cia.new_setpoint(self.units.position_to_internal(target), relative=relative)
            elif not cw & 0x10:
                self.cia.setpoint_ack = False
        hh.on_controlword(self, cw, prev)
        self._refresh_inputs()

    def _on_mode(self, sub: int, value: int | None) -> None:
        if not self.behaviour.mode_display_on_enable or self.cia.state is State.OPERATION_ENABLED:
            self._put(0x6061, 0, value or 0)
        hh.on_mode(self)
        self._refresh_inputs()

    def _check_mode(self, sub: int, data: bytes, value: int | None) -> bool:
        mode = value or 0
        if self.behaviour.mode_locked_when_enabled and self.cia.state in (State.OPERATION_ENABLED, State.QUICK_STOP) \
                and mode != self.mode():
            raise _abort(0x6060, sub, A.DATA_CANNOT_BE_STORED_STATE)
        supported = self.rules.supported_modes
        if supported and mode not in supported and mode != 0:
            if self.behaviour.unsupported_mode_emcy is not None:
                self.emcy(self.behaviour.unsupported_mode_emcy)
            else:
                raise _abort(0x6060, sub, A.INVALID_VALUE)
        return True

    def _check_homing_method(self, sub: int, data: bytes, value: int | None) -> bool:
        hh.check_method(self, sub, value or 0)
        return True

    def _check_min_max(self, sub: int, data: bytes, value: int | None) -> bool:
        """HDT §4.11.6: 6046h max <= min is refused with 0609 0030h."""
        other = self._read_int(0x6046, 2 if sub == 1 else 1) or 0
        lo, hi = (value or 0, other) if sub == 1 else (other, value or 0)
        if sub in (1, 2) and hi <= lo:
            raise _abort(0x6046, sub, A.INVALID_VALUE)
        return True

    def _check_store_signature(self, sub: int, data: bytes, value: int | None) -> bool:
        """CiA-301 1010h (HDT §2.08.1.a): a store command is the signature "save" (65766173h, bytes 73 61 76
        65 on the wire); anything else is refused with 0800 0020h."""
        if sub and value != 0x65766173:
            raise _abort(0x1010, sub, A.DATA_CANNOT_BE_STORED)
        return True

    def _copy_min_max_amount(self, sub: int, value: int | None) -> None:
        """Control Techniques 7.5.4: writing 6046h sub 1 (sub 2) overwrites 6047h sub 1 and 3 (2 and 4)."""
        if sub in (1, 2):
            for target in (sub, sub + 2):
                self._put(0x6047, target, value or 0)

    @staticmethod
    def _nonzero(index: int) -> Callable[[int, bytes, int | None], bool]:
        """Control Techniques 7.5.9/7.5.10: a 0 in 604Bh/604Ch is invalid (code not stated: 0609 0030h)."""
        def check(sub: int, data: bytes, value: int | None) -> bool:
            if sub and not value:
                raise _abort(index, sub, A.INVALID_VALUE)
            return True
        return check

    def _check_interpolation_period(self, sub: int, data: bytes, value: int | None) -> bool:
        """The family's interpolation periods (``FamilyRules.accepts_ip_period``; Control Techniques 7.4.3:
        250 us, 500 us or k x 1 ms); any other value is refused (code not stated: 0609 0030h). Checked on each
        write, with the other sub-index as stored."""
        if sub not in (1, 2):
            return True
        base = (value or 0) if sub == 1 else (self._read_int(0x60C2, 1) or 0)
        exp = (value or 0) if sub == 2 else (self._read_int(0x60C2, 2) or 0)
        if not -9 <= exp <= 2:
            return True  # the entry's own range check answers
        if not self.rules.accepts_ip_period(interpolation_period_ns(base, exp)):
            raise _abort(0x60C2, sub, A.INVALID_VALUE)
        return True

    def configure_dc(self, assign_activate: int, sync0_cycle_ns: int = 0, sync0_shift_ns: int = 0) -> None:
        """What the master writes to the ESC before SAFE-OP: DC activation (0x0981, e.g. 0x0300 = SYNC0)
        and the SYNC0 cycle and shift times in ns. ``assign_activate = 0`` = free run."""
        self.dc = (assign_activate, sync0_cycle_ns)
        self.dc_shift_ns = sync0_shift_ns
        self._log("dc", assign_activate=assign_activate, sync0_cycle_ns=sync0_cycle_ns, sync0_shift_ns=sync0_shift_ns)

    def _check_dc(self) -> None:
        active, cycle = getattr(self, "dc", (0, 0))
        if self.family == "controltechniques" and active:
            # 8.1.1: SYNC0 = n x 250 us, n = 1..60
            if cycle <= 0 or cycle % 250_000 or not 1 <= cycle // 250_000 <= 60:
                self._refuse(EcState.OP, AL_DC_INVALID_CYCLE, f"SYNC0 cycle {cycle} ns is not n x 250 us (n = 1..60)")
        if not active and self.has_cia402 and self.mode() in self.rules.dc_required_modes:
            self._refuse(EcState.OP, AL_DC_INVALID_SYNC, f"mode {self.mode()} needs distributed clocks")

    def mode(self) -> int:
        # every dictionary entry has a stored value, so 6061h reads as an int whenever the drive has it
        index = 0x6061 if (0x6061, 0) in self._entries else 0x6060
        return self._read_int(index, 0) or 0

    def step(self, cycles: int = 1) -> None:
        """Advance the motion model by ``cycles`` process-data cycles (see :meth:`cycle_time`)."""
        if not self.has_cia402:
            return
        dt = self.cycle_time()
        u = self.units
        for _ in range(cycles):
            mode = self.mode()
            homing_before = self.cia.homing
            self.cia.step(
                mode, dt,
                target_position=u.position_to_internal((self._read_int(0x607A, 0) or 0) - self._home_offset()
                                                       if mode == CSP else 0),
                target_velocity=u.velocity_to_internal(self._read_int(0x60FF, 0) or 0),
                profile_velocity=u.velocity_to_internal(self._read_int(0x6081, 0) or 0),
                acceleration=u.acceleration_to_internal(self._read_int(0x6083, 0) or 0),
                inc_per_s=u.increments_per_second, vel_from_inc_per_s=u.velocity_from_increments_per_second,
                inc_per_s2=u.increments_per_second2, halt_deceleration=hh.halt_decel_for_step(self, mode),
            )
            if homing_before is not self.cia.homing:
                hh.after_step(self, homing_before)
        self._refresh_inputs()

    def _refresh_inputs(self) -> None:
        """Actual values from the state: 6041h, 6063h/6064h, 606Ch, 603Fh."""
        if not getattr(self, "has_cia402", False):
            return
        mode = self.mode()
        sw = self.cia.statusword(mode=mode) | (0x0800 if self.limit_active else 0)
        if self.family == "technosoft-ipos" and mode == HOMING and self.cia.homing is Homing.IN_PROGRESS:
            sw |= 0x0100 | (0x0080 if self.homing_warning else 0)  # §4.2.2 bit 8 homing executing, 7 warning
        self._put(0x6041, 0, sw)
        u = self.units
        self._put(0x6063, 0, to_int(self.cia.position))
        user_position = self._user_position()
        self._put(0x6064, 0, user_position)
        self._put(0x6062, 0, user_position)
        self._put(0x606C, 0, to_int(u.velocity_to_user(self.cia.velocity)))
        self._put(0x603F, 0, self.cia.fault_code)

    def _home_offset(self) -> int:
        """607Ch where the family adds it to the measured position at all times (HDT), else 0."""
        if not self.behaviour.home_offset_continuous:
            return 0
        return self._read_int(0x607C, 0) or 0

    def _user_position(self) -> int:
        """6064h: the position in user units (HDT: sensor position + home offset 607Ch, §4.06.6)."""
        return to_int(self.units.position_to_user(self.cia.position)) + self._home_offset()

    @property
    def internal_position(self) -> int:
        """Position in the drive's internal units (increments), truncated as the drive stores it."""
        return to_int(self.cia.position)

    @property
    def internal_velocity(self) -> int:
        """Velocity in internal units (Technosoft: 16.16 increments per slow-loop sample)."""
        return to_int(self.cia.velocity)

    @property
    def cia402_state(self) -> State:
        return self.cia.state

    def inject_fault(self, code: int, data: bytes = b"") -> None:
        """A drive fault: FAULT REACTION ACTIVE -> FAULT, 603Fh = code, EMCY with the code."""
        self._cia_moves(self.cia.fault(code), f"fault 0x{code:04X}")
        self.emcy(code, data)
        self._refresh_inputs()

    def lose_communication(self) -> None:
        """Fault injection: the process data stops (cable pulled, SM watchdog). The ESM drops from OP to
        SAFE-OP (AL status 0x001B) and the drive reacts with its abort connection option code 6007h:
        0 no action, 1 fault (EMCY 0x8100), 2 disable voltage, 3 quick stop, unless the family's
        rules say otherwise (HDT 3: quick-stop ramp and stay enabled); Control Techniques always ends in
        SWITCH ON DISABLED (7.3.1)."""
        if self.esm is EcState.OP:
            self._log("state", previous="OP", state="SAFEOP", al_status=0x001B, reason="sync manager watchdog")
            self.esm = EcState.SAFEOP
            self._esm_effects(EcState.OP, EcState.SAFEOP)
        if not self.has_cia402:
            return
        option = self._read_int(0x6007, 0)
        option = 1 if option is None else option
        end = self.option_end_state(0x6007, option,
                                    {0: "NO_ACTION", 1: "FAULT", 2: "SWITCH_ON_DISABLED"}.get(option, "QUICK_STOP"))
        if self.family == "controltechniques":
            end = "SWITCH_ON_DISABLED"
        self._log("cia402", reason=f"communication lost, 6007h = {option}", reaction=end)
        if end == "FAULT":
            self.inject_fault(0x8100)
        elif end == "SWITCH_ON_DISABLED":
            self._cia_moves(self.cia.communication_lost(), "communication lost")
        elif end == "QUICK_STOP" and self.cia.state is State.OPERATION_ENABLED:
            self._cia_moves(self.cia.controlword_written(self.cia.controlword & ~0x04 | 0x02, ecat_op=False,
                                                        quick_stop_option=self._read_int(0x605A, 0) or 2),
                            "communication lost: quick stop")
        elif end == "OPERATION_ENABLED":
            self.cia.velocity = Fraction(0)
            self.cia.target = None
            self.cia.interrupt_homing()
        self._refresh_inputs()

    def option_end_state(self, index: int, option: int, default: str) -> str:
        """The end state the family rules give an option code (``option_code_end_states``), else ``default``."""
        for i, v, end in getattr(self.rules, "option_code_end_states", ()):
            if i == index and v == option:
                return str(end)
        return default

    def set_limit_switches(self, *, negative: bool = False, positive: bool = False) -> None:
        """The limit-switch inputs change: 60FDh bits per the family (HDT swaps them: bit 0 = CW =
        positive); Technosoft sends EMCY 0x5442/0x5443 when one becomes active and 0x0000 when it clears
        (§3.1.3), and statusword bit 11 (internal limit active) follows."""
        neg_bit, pos_bit = self.rules.limit_switch_bits
        old = self._read_int(0x60FD, 0) or 0
        new = old & ~((1 << neg_bit) | (1 << pos_bit))
        new |= (negative << neg_bit) | (positive << pos_bit)
        self._put(0x60FD, 0, new)
        was_neg, was_pos = bool(old >> neg_bit & 1), bool(old >> pos_bit & 1)
        self.limit_active = negative or positive
        self.limit_switches = (negative, positive)
        self._log("inputs", digital_inputs=new)
        if self.family == "technosoft-ipos":
            for was, now, code in ((was_neg, negative, 0x5442), (was_pos, positive, 0x5443)):
                if now and not was:
                    self.emcy(code)
                elif was and not now:
                    self.emcy(0x0000)
        hh.on_limit_switches(self)
        self._refresh_inputs()

    def inject_hdt_alarm(self, alarm: int, code: int) -> None:
        """HDT: alarm FA_n with EMCY ``code``; EMCY bytes 3..6 carry the alarm bitmap (bit n-1)."""
        self.inject_fault(code, (1 << (alarm - 1)).to_bytes(4, "little") + b"\x00")

    def inject_trip(self, trip: int) -> None:
        """Control Techniques: drive trip number -> 603Fh per Table 9.17 (unlisted trips 0x1000)."""
        self.inject_fault(CT_TRIP_CODES.get(trip, 0x1000))

    # ------------------------------------------------------------------------------------------
    # Technosoft memory objects, reset, FoE
    # ------------------------------------------------------------------------------------------
    def _install_handlers(self) -> None:
        self._after_write: dict[int, Callable[[int, int | None], None]] = {
            0x6040: self._on_controlword,
            0x6060: self._on_mode,
        }
        self._handlers_down[0x6060] = self._check_mode
        self._handlers_down[0x6098] = self._check_homing_method
        self._handlers_down[0x1010] = self._check_store_signature
        if self.behaviour.home_offset_continuous:
            self._after_write[0x607C] = lambda sub, value: self._refresh_inputs()  # 6064h = sensor + 607Ch
        if self.family == "hdt":
            self._handlers_down[0x6046] = self._check_min_max
        if self.rules.ip_periods_ns or self.rules.ip_period_step_ns:
            self._handlers_down[0x60C2] = self._check_interpolation_period
        if self.family == "controltechniques":
            self._handlers_down[0x604B] = self._nonzero(0x604B)
            self._handlers_down[0x604C] = self._nonzero(0x604C)
            self._after_write[0x6046] = self._copy_min_max_amount
        if self.family != "technosoft-ipos":
            return
        m = self.memory

        def memory_op(index: int, op: Callable[[int], Any]) -> Callable[[int, bytes, int | None], bool]:
            def handler(sub: int, data: bytes, value: int | None) -> bool:
                try:
                    op(value or 0)
                except ee.EepromLocked:
                    raise _abort(index, sub, A.DATA_CANNOT_BE_STORED) from None
                except ee.PowerLost:
                    raise
                self._sync_memory_objects()
                self._log("eeprom", object=f"0x{index:04X}", value=value)
                return index not in (0x2065, 0x2067)
            return handler

        def set_config(v: int) -> None:
            m.config = v

        def set_lock(v: int) -> None:
            m.locked = bool(v & 1)

        def checksum(v: int) -> None:
            if (v >> 16) < (v & 0xFFFF):
                raise _abort(0x2069, 0, A.INVALID_VALUE)
            m.compute_checksum(v)

        self._handlers_down[0x2064] = memory_op(0x2064, set_config)
        self._handlers_down[0x2065] = memory_op(0x2065, self._eeprom_guarded(m.write_2065))
        self._handlers_down[0x2067] = memory_op(0x2067, self._eeprom_guarded(m.write_2067))
        self._handlers_down[0x2069] = memory_op(0x2069, checksum)
        self._handlers_down[0x2091] = memory_op(0x2091, set_lock)
        self._handlers_down[0x2080] = self._reset_object

        def read_2066(sub: int) -> bytes:
            v = m.read_2066()
            self._sync_memory_objects()
            return v.to_bytes(4, "little")

        self._handlers_up[0x2066] = read_2066

    def _eeprom_guarded(self, op: Callable[[int], None]) -> Callable[[int], None]:
        def run(value: int) -> None:
            if self.faults.eeprom_power_loss_after is not None:
                self.memory.power_loss_after = self.faults.eeprom_power_loss_after
                self.faults.eeprom_power_loss_after = None
            op(value)
        return run

    def _sync_memory_objects(self) -> None:
        m = self.memory
        self._put(0x2064, 0, m.config)
        self._put(0x206A, 0, m.checksum)
        self._put(0x2091, 0, int(m.locked))
        if (0x2002, 0) in self._entries:
            der = self._read_int(0x2002, 0) or 0
            self._put(0x2002, 0, (der | 0x8000) if m.locked else (der & 0x7FFF))

    def _reset_object(self, sub: int, data: bytes, value: int | None) -> bool | None:
        if not value:
            return True
        self.reset()
        return None

    def reset(self) -> None:
        """2080h: reset the drive (not the EtherCAT interface). RAM objects return to their defaults; the
        EEPROM keeps what was written, so the setup after the reset is what the EEPROM holds."""
        self._log("reset", reason="drive reset")
        locked = self.memory.locked
        layout = self.layout
        self._reset_application()
        self.memory.locked = locked
        self._sync_memory_objects()
        self.layout = layout

    def _power_loss(self) -> None:
        self._log("power_loss", esm=self.esm.value)
        self.memory.power_loss_after = None
        self._power_on()

    def power_cycle(self) -> None:
        """Switch the drive off and on: ESM back to INIT, RAM lost, EEPROM kept."""
        self._power_loss()

    def eeprom_words(self, start: int, count: int) -> list[int]:
        return [self.memory.read_word(ee.EEPROM, start + i) for i in range(count)]

    def foe_write(self, name: str, data: bytes, password: int = 0) -> None:
        """An FoE download. Setup files (FOESW_…, password 0) are accepted in PRE-OP/SAFE-OP/OP, and in
        BOOT only when 210Ch = 1; firmware files (FOEFW_…) only in BOOT with the firmware password."""
        self._log("foe", name=name, bytes=len(data), password=password, esm=self.esm.value)
        if self.device.mailbox is None or "FoE" not in self.device.mailbox.protocols:
            raise FoeError(name, ee.FOE_NOT_DEFINED, "the device has no FoE mailbox")
        if self.esm is EcState.INIT:
            raise FoeError(name, ee.FOE_ACCESS_DENIED, "no mailbox in INIT")
        setup_in_boot = (self._read_int(0x210C, 0) or 0) == 1
        if self.esm is EcState.BOOT and not setup_in_boot:
            if not ee.is_firmware_name(name):
                raise FoeError(name, ee.FOE_ILLEGAL, "in BOOT the drive expects a FOEFW_ firmware file (210Ch = 0)")
            if password not in ee.FIRMWARE_PASSWORDS:
                raise FoeError(name, ee.FOE_NO_RIGHTS, f"wrong firmware password 0x{password:08X}")
            self._log("foe", name=name, result="firmware accepted")
            return
        if ee.is_firmware_name(name):
            raise FoeError(name, ee.FOE_BOOTSTRAP_ONLY, "firmware files are accepted only in BOOT")
        why = ee.check_setup_name(name)
        if why:
            raise FoeError(name, ee.FOE_ILLEGAL, why)
        if password != 0:
            raise FoeError(name, ee.FOE_NO_RIGHTS, "setup files need password 0")
        if self.memory.locked:
            raise FoeError(name, ee.FOE_ACCESS_DENIED, "the EEPROM is locked (2091h)")
        try:
            blocks = ee.parse_foe_setup(data)
        except ValueError as exc:
            raise FoeError(name, ee.FOE_ILLEGAL, str(exc)) from None
        for start, words in blocks:
            for i, w in enumerate(words):
                self.memory.eeprom[(start + i) & 0xFFFF] = w
        self._log("foe", name=name, result="setup written", blocks=[(b[0], len(b[1])) for b in blocks])
