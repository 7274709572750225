"""The :class:`Drive`: one simulated EtherCAT CoE slave, the pieces of the drive application combined.

A :class:`Drive` is built from a :class:`~ecattool.esi.model.Device` (from an ESI or a built-in profile) and
the family's :class:`~ecattool.profiles.rules.FamilyRules`. It shares that *data* with the PDO checker but
makes its own decisions: every SDO is accepted or aborted with the code the drive sends, SAFE-OP is refused
with the AL status code the drive sets. It satisfies :class:`ecattool.target.base.SlaveTarget`.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from ecattool.esi.model import Device, Identity
from ecattool.od.model import EcState, Entry
from ecattool.profiles.rules import FamilyRules
from ecattool.sim import eeprom as ee
from ecattool.sim.cia402 import Cia402
from ecattool.sim.drive.behaviour import BEHAVIOURS
from ecattool.sim.drive.core import RX, TX, Layout, Store
from ecattool.sim.drive.esm import StateMachine
from ecattool.sim.drive.family import FamilyQuirks
from ecattool.sim.drive.injection import Injection
from ecattool.sim.drive.memory import Memory
from ecattool.sim.drive.mode_parts import ModeParts
from ecattool.sim.drive.modules import expand_default_modules
from ecattool.sim.drive.motion import Motion
from ecattool.sim.drive.process_data import ProcessData
from ecattool.sim.drive.sdo import SdoServer
from ecattool.sim.faults import Faults
from ecattool.sim.units import units_for


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


class Drive(SdoServer, ProcessData, StateMachine, Motion, Injection, FamilyQuirks, Memory):
    """A simulated EtherCAT CoE slave (a servo drive when its dictionary has the CiA-402 objects)."""

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
        self.events = []
        self.emergencies = []
        self.memory = ee.Memory()
        self._seq = 0
        self._pdo_known = self._known_pdo_entries()
        self._fixed = {p.index for p in (*device.rx_pdos, *device.tx_pdos) if p.fixed}
        self._pdo_only_set = frozenset(getattr(self.rules, "pdo_only_indices", ()))
        self._read_only_set = frozenset(getattr(self.rules, "read_only_indices", ()))
        self._handlers_down = {}
        self._handlers_up = {}
        self._after_write = {}
        self._install_motion_handlers()
        self._install_family_handlers()
        self._install_memory_handlers()
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
    def from_esi(cls, path: str | Path, selector: str | None = None, policy: str = "exact", **kw: Any) -> "Drive":
        from ecattool import esi

        device = esi.load_device(path, selector, policy)
        return cls(_complete(expand_default_modules(device)), **kw)

    # ------------------------------------------------------------------------------------------
    # power on / reset
    # ------------------------------------------------------------------------------------------
    def _power_on(self) -> None:
        self.esm = EcState.INIT
        self._reset_application()

    def _reset_application(self) -> None:
        """Dictionary to defaults, PDO configuration from the device description, CiA-402 restarted."""
        d = self.device
        self._store = Store()
        self._entries = {}
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
        self.layout = {RX: Layout(), TX: Layout()}
        self.cia = Cia402(enable_needs_op=self.behaviour.enable_needs_op,
                          supply_bit_always=self.behaviour.supply_bit_always)
        self.modes = ModeParts()
        self.limit_active = False
        self.limit_switches = (False, False)  # (negative, positive) inputs, set_limit_switches()
        self.homing_warning = False  # Technosoft statusword bit 7 (homing start ignored)
        self.has_cia402 = (0x6040, 0) in self._entries and (0x6041, 0) in self._entries
        self.units = units_for(self.behaviour.units, self._read_int, revision=d.revision,
                             has_210f=0x210F in d.dictionary, cycle_s=self.cycle_time())
        self.units.version = lambda: self._store.version
        if not self.behaviour.mode_display_on_enable and (0x6061, 0) in self._entries:
            # 6061h shows the mode 6060h selects from power-on (HDT §4.02.2, CT Table 7.16: 6060h = 2 by
            # default, and that mode is the one the drive runs)
            self._put(0x6061, 0, self._read_int(0x6060, 0) or 0)
        for (index, sub), other in self.behaviour.linked_objects:
            self._put(*other, self._read_int(index, sub) or 0)  # Pr 1.06 = 6080h's default (CT 7.3.17)
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

    # ------------------------------------------------------------------------------------------
    # SlaveTarget
    # ------------------------------------------------------------------------------------------
    def identity(self) -> Identity:
        return self.device.identity
