"""The :class:`Drive`: one simulated EtherCAT CoE slave, the pieces of the drive application combined.

A :class:`Drive` is built from a :class:`~ecattool.esi.model.Device` (from an ESI or a built-in profile) and
the family's :class:`~ecattool.profiles.rules.FamilyRules`. It shares that *data* with the PDO checker but
makes its own decisions: every SDO is accepted or aborted with the code the drive sends, SAFE-OP is refused
with the AL status code the drive sets. It satisfies :class:`ecattool.target.base.SlaveTarget`.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Literal

from ecattool.esi.model import Device, Direction, Identity
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
from ecattool.sim.drive.motion import Motion
from ecattool.sim.drive.plant import Plant, PlantParams, plant_for
from ecattool.sim.drive.plant_step import counts_per_rev
from ecattool.sim.drive.process_data import ProcessData
from ecattool.sim.drive.supervision_state import Supervision
from ecattool.sim.drive.sdo import SdoServer
from ecattool.sim.faults import Faults
from ecattool.sim.units import units_for


#: the torque limits of CiA-402 (per mille of the rated torque 6076h)
_TORQUE_LIMITS = (0x6072, 0x60E0, 0x60E1)


def _rules_for(device: Device) -> FamilyRules:
    try:
        from ecattool.profiles import rules_for
    except ImportError:
        return FamilyRules("generic", vendor_id=device.vendor_id)
    return rules_for(device)


def _standard_entry(sub: int, bits: int, d: Direction) -> Entry:
    """A read-only entry of ``bits`` (BOOL for one bit, else BITn or the unsigned type of that size) mappable
    in direction ``d``."""
    from ecattool.od.model import RO
    from ecattool.od.types import lookup

    name = {1: "BOOL", 8: "USINT", 16: "UINT", 32: "UDINT", 64: "ULINT"}.get(bits, f"BIT{bits}")
    dt = lookup(name)
    return Entry(sub, f"standard object sub {sub}", dt, bits, name, pdo_mapping="R" if d is Direction.RX else "T",
                 access=RO)


class Drive(SdoServer, ProcessData, StateMachine, Motion, Injection, FamilyQuirks, Memory):
    """A simulated EtherCAT CoE slave (a servo drive when its dictionary has the CiA-402 objects)."""

    def __init__(self, device: Device, rules: FamilyRules | None = None, *, position: int = 0,
                 strict_pdo_length: bool = True, record_events: bool = True,
                 plant: PlantParams | Literal["ideal"] | None = None) -> None:
        """``plant``: the motor and load between demand and actual values (None: the family's default plant,
        :func:`~ecattool.sim.drive.plant.plant_for`; ``"ideal"``: none, the actual values are the demand)."""
        self.device = device
        self.rules = rules if rules is not None else _rules_for(device)
        self.family = self.rules.family if self.rules.family in BEHAVIOURS else "generic"
        self.behaviour = BEHAVIOURS[self.family]
        self.position = position
        self.strict_pdo_length = strict_pdo_length
        self.record_events = record_events
        self.faults = Faults()
        self._plant_params = self._params_of(plant)
        self.events = []
        self.emergencies = []
        self.memory = ee.Memory()
        self._seq = 0
        self._pdo_known = self._known_pdo_entries()
        self._fixed = {p.index for p in (*device.rx_pdos, *device.tx_pdos) if p.fixed}
        self._pdo_only_set = self.rules.pdo_only_indices
        self._read_only_set = self.rules.read_only_indices
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
        """A drive of ``device`` as it runs (:func:`ecattool.profiles.running.as_running`: an ESI device gets its
        default modules and the communication objects its ESI leaves out, exactly as :meth:`from_esi` does;
        built-in profile devices, and devices the resolver already gave, are used as they are)."""
        from ecattool.profiles.running import as_running

        return cls(as_running(device), rules, **kw)

    @classmethod
    def from_profile(cls, name: str, product: str | None = None, revision: str | int | None = None,
                     **kw: Any) -> "Drive":
        from ecattool import profiles
        from ecattool.profiles.running import device_from_profile

        device = device_from_profile(name, product=product, revision=revision)
        return cls(device, profiles.rules_for(device), **kw)

    @classmethod
    def from_esi(cls, path: str | Path, selector: str | None = None, policy: str = "exact", **kw: Any) -> "Drive":
        from ecattool.profiles.running import device_from_file

        return cls(device_from_file(path, selector, policy=policy), **kw)

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
        for direction, dset in self._pdo_known.items():
            for idx, sub, bits in dset:
                self._store.setdefault((idx, sub), b"\x00" * ((bits + 7) // 8))
                if 0x1000 <= idx <= 0x1FFF and (idx, sub) not in self._entries:
                    # a communication object the ESI's dictionary leaves out but its PDO list maps (a TxPDO's
                    # state and toggle 1800h:07/09, 1C32h:20h sync error): the slave has it, by SDO too
                    self._entries[(idx, sub)] = _standard_entry(sub, bits, direction)
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
        self._new_plant()
        self._refresh_inputs()

    def _new_plant(self) -> None:
        """The plant at rest (power-on, reset, new parameters) and the supervision's memory cleared."""
        params = self._plant_params
        self.supervision = Supervision()
        self._demand_before = (self.cia.pos_n, self.cia.pos_d)
        if params is None or not self.has_cia402:
            self.plant = None
            return
        dt = self.cycle_time()
        self.plant = Plant(params, counts_per_rev(self), dt.numerator / dt.denominator)
        for index in _TORQUE_LIMITS:
            self._after_write[index] = self._on_torque_limit
        self._on_torque_limit(0, None)

    def _on_torque_limit(self, sub: int, value: int | None) -> None:
        """6072h max torque and 60E0h/60E1h positive/negative torque limits (per mille of the rated torque; 0 or
        absent: none) limit the plant's torque, at most its peak torque (one symmetric limit: the smallest)."""
        plant = self.plant
        if plant is None:
            return
        limit = plant.params.peak_torque
        for index in _TORQUE_LIMITS:
            raw = self._read_int(index, 0) if (index, 0) in self._entries else None
            if raw:
                limit = min(limit, abs(raw) / 1000 * plant.params.rated_torque)
        plant.torque_limit = limit

    def set_plant(self, plant: PlantParams | Literal["ideal"] | None = None) -> None:
        """Put the drive on another plant (None: the family's default; ``"ideal"``: the exact tracker). The axis
        keeps its position; the plant starts at rest on the demand."""
        self._plant_params = self._params_of(plant)
        self._new_plant()
        self._refresh_inputs()

    def _params_of(self, plant: PlantParams | Literal["ideal"] | None) -> PlantParams | None:
        if plant == "ideal":
            return None
        return plant if isinstance(plant, PlantParams) else plant_for(self.family)

    @property
    def plant_params(self) -> PlantParams | None:
        """The plant's parameters (None: the ideal tracker)."""
        return self._plant_params

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
