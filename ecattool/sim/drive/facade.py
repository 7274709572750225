"""The :class:`Drive`: one simulated EtherCAT CoE slave, the pieces of the drive application combined.

A :class:`Drive` is built from a :class:`~ecattool.esi.model.Device` (from an ESI or a built-in profile) and
the family's :class:`~ecattool.profiles.rules.FamilyRules`. It shares that *data* with the PDO checker but
makes its own decisions: every SDO is accepted or aborted with the code the drive sends, SAFE-OP is refused
with the AL status code the drive sets. It satisfies :class:`ecattool.target.base.SlaveTarget`.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from fractions import Fraction
from pathlib import Path
from typing import Any, Literal

from ecattool import profiles
from ecattool.errors import TargetError
from ecattool.esi.model import Device, Direction, Identity
from ecattool.od.model import RO, EcState, Entry
from ecattool.od.types import lookup
from ecattool.profiles.rules import FamilyRules
from ecattool.sim import eeprom as ee
from ecattool.sim.cia402 import Cia402, State
from ecattool.sim.drive.core import RX, TX, Emergency, Event, EventLog, Layout, ObjectStore, Store
from ecattool.sim.drive.esm import StateMachine
from ecattool.sim.drive.family import Family
from ecattool.sim.drive.injection import Injection
from ecattool.sim.drive.io_app import IoApplication, mapped_values
from ecattool.sim.drive.memory import Memory
from ecattool.sim.drive.mode_parts import ModeParts
from ecattool.sim.drive.motion import Motion
from ecattool.sim.drive.pdo import PdoConfig
from ecattool.sim.drive.plant import Plant, PlantParams
from ecattool.sim.drive.plant_step import counts_per_rev
from ecattool.sim.drive.process_data import ProcessData
from ecattool.sim.drive.sdo import SdoServer
from ecattool.sim.drive.supervision_state import Supervision
from ecattool.sim.faults import Faults
from ecattool.sim.units import Units, units_for

#: the torque limits of CiA-402 (per mille of the rated torque 6076h)
_TORQUE_LIMITS = (0x6072, 0x60E0, 0x60E1)


def _rules_for(device: Device) -> FamilyRules:
    try:
        from ecattool.profiles import rules_for
    except ImportError:
        return FamilyRules("generic", vendor_id=device.vendor_id)
    return rules_for(device)


def has_cia402(device: Device) -> bool:
    """Whether ``device`` is a CiA-402 drive (its dictionary has the controlword 6040h and the statusword 6041h):
    it runs the drive application, else the I/O application (:class:`~.io_app.IoApplication`)."""
    indices = {obj.index for obj in device.dictionary if 0 in obj.entries}
    return 0x6040 in indices and 0x6041 in indices


def _standard_entry(sub: int, bits: int, d: Direction) -> Entry:
    """A read-only entry of ``bits`` (BOOL for one bit, else BITn or the unsigned type of that size) mappable
    in direction ``d``."""
    name = {1: "BOOL", 8: "USINT", 16: "UINT", 32: "UDINT", 64: "ULINT"}.get(bits, f"BIT{bits}")
    dt = lookup(name)
    return Entry(sub, f"standard object sub {sub}", dt, bits, name, pdo_mapping="R" if d is Direction.RX else "T",
                 access=RO)


class Drive:
    """A simulated EtherCAT CoE slave (a servo drive when its dictionary has the CiA-402 objects).

    A facade over the parts of the drive application, each an object built and wired together here (none inherits
    another): the object store (:class:`~.core.ObjectStore`), the event log and emergencies
    (:class:`~.core.EventLog`), the family (:class:`~.family.Family`, chosen once from the family's data), the PDO
    configuration (:class:`~.pdo.PdoConfig`), SDO access (:class:`~.sdo.SdoServer`), the process data
    (:class:`~.process_data.ProcessData`), the ESM (:class:`~.esm.StateMachine`), the CiA-402 device control and
    motion (:class:`~.motion.Motion`, with the mode parts, the profile generators of :class:`~ecattool.sim.cia402.
    Cia402`, the plant and the supervision), faults and inputs (:class:`~.injection.Injection`) and the memory
    (:class:`~.memory.Memory`). The drive holds the state the parts share, which a power-on or a reset renews:
    the ESM state, the CiA-402 model, the mode parts, the plant, the unit conversions, the process image layout.

    The application is chosen once, from the device (:func:`has_cia402`): a slave without 6040h/6041h (a terminal,
    a coupler) holds the I/O application (:class:`~.io_app.IoApplication`, ``io``) instead of the motion and fault
    parts, and has no CiA-402 model, units, plant or supervision; its process data is its object store as mapped,
    and a call only an axis answers is a one-line :class:`~ecattool.errors.TargetError`."""

    #: seconds a homing method searches for its switch or index pulse before it reports a homing error
    #: (the simulated axis has none connected; docs/decisions.md)
    homing_search_s = Fraction(1)

    # -- the state the parts share, renewed at power-on / reset ------------------------------------
    esm: EcState
    layout: dict[Direction, Layout]
    cia: Cia402
    limit_active: bool
    limit_switches: tuple[bool, bool]
    homing_warning: bool
    has_cia402: bool
    units: Units
    #: the motor and load between demand and actual values (None: the ideal tracker, actual = demand)
    plant: Plant | None
    supervision: Supervision
    _demand_before: tuple[int, int]
    #: the store's version, the mode and the polarity signs at them (:func:`.polarity.target_signs`)
    _polarity_cache: tuple[int, int, tuple[int, int]] = (0, 0, (1, 1))
    # -- the application, chosen once from the device (:func:`has_cia402`): a drive holds the motion and fault
    # parts (and ``cia``, ``units``, ``supervision`` above), an I/O slave the I/O application instead
    motion: Motion
    injection: Injection
    io: IoApplication | None

    def __init__(self, device: Device, rules: FamilyRules | None = None, *, position: int = 0,
                 strict_pdo_length: bool = True, record_events: bool = True,
                 plant: PlantParams | Literal["ideal"] | None = None) -> None:
        """``plant``: the motor and load between demand and actual values (None: the family's default plant,
        :func:`~ecattool.sim.drive.plant.plant_for`; ``"ideal"``: none, the actual values are the demand)."""
        self.device = device
        self.position = position
        self.strict_pdo_length = strict_pdo_length
        self.faults = Faults()
        self.memory = ee.Memory()
        # the parts, each given what it works with
        self.objects = objects = ObjectStore()
        self.event_log = log = EventLog(objects, record_events)
        self.family_part = family = Family(self, rules if rules is not None else _rules_for(device))
        self.rules: FamilyRules = family.rules
        self.family: str = family.name
        self.behaviour = family.behaviour
        self.pdo = PdoConfig(self)
        self.sdo = SdoServer(self, self.pdo)
        self.has_cia402 = has_cia402(device)
        self.process_data = ProcessData(self, self.pdo)
        self.state_machine = StateMachine(self)
        self.nonvolatile = Memory(self)
        # what every part calls on the others, bound once (the cycle calls them without a facade in between)
        self._read_int: Callable[[int, int], int | None] = objects.read_int
        self._put: Callable[[int, int, int], None] = objects.put
        self._put_all: Callable[[tuple[tuple[int, int], ...], tuple[int, ...]], None] = objects.put_all
        self._log: Callable[..., None] = log.log
        if self.has_cia402:
            # a drive: CiA-402 device control and motion (with the plant and the supervision), faults and inputs
            self.io = None
            self.motion = motion = Motion(self)
            self.injection = Injection(self)
            self._refresh_inputs: Callable[..., None] = motion._refresh_inputs
            self._cia_moves: Callable[[list[tuple[State, State]], str], None] = motion._cia_moves
            self._home_offset: Callable[[], int] = motion._home_offset
            self._user_position: Callable[[], int] = motion._user_position
        else:
            # an I/O slave: its process data is its object store as mapped; nothing is stepped
            self.io = io = IoApplication(self)
            self._refresh_inputs = io.refresh
            self.plant = None
            self.limit_active = False
            self.limit_switches = (False, False)
        self._plant_params = self._params_of(plant) if self.has_cia402 else None
        self._pdo_known = self.pdo.known_entries()
        self._fixed = {p.index for p in (*device.rx_pdos, *device.tx_pdos) if p.fixed}
        self._pdo_only_set = self.rules.pdo_only_indices
        self._read_only_set = self.rules.read_only_indices
        #: SDO download handlers: True to store the value, False to skip storing it, None when the drive does
        #: not reply; upload handlers return the bytes; after-write reactions run once the value is stored
        self._handlers_down: dict[int, Callable[[int, bytes, int | None], bool | None]] = {}
        self._handlers_up: dict[int, Callable[[int], bytes]] = {}
        self._after_write: dict[int, Callable[[int, int | None], None]] = {}
        if self.io is None:
            self.motion.install_handlers()
        family.install_handlers()
        self.nonvolatile.install_handlers()
        self._power_on()

    def _axis(self, what: str) -> Motion:
        """The motion part, or the one-line error that an I/O slave has none (``what``: the call)."""
        if self.io is not None:
            raise self.io.no_axis(what)
        return self.motion

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
        store = self.objects.store = Store()
        entries: dict[tuple[int, int], Entry] = {}
        self.objects.entries = entries
        for obj in d.dictionary:
            for e in obj.entries.values():
                entries[(obj.index, e.subindex)] = e
                store[(obj.index, e.subindex)] = self._default_bytes(e)
        for direction, dset in self._pdo_known.items():
            for idx, sub, bits in dset:
                store.setdefault((idx, sub), b"\x00" * ((bits + 7) // 8))
                if 0x1000 <= idx <= 0x1FFF and (idx, sub) not in entries:
                    # a communication object the ESI's dictionary leaves out but its PDO list maps (a TxPDO's
                    # state and toggle 1800h:07/09, 1C32h:20h sync error): the slave has it, by SDO too
                    entries[(idx, sub)] = _standard_entry(sub, bits, direction)
        self._identity_defaults()
        self.family_part.report_encoder_resolution()
        self.pdo.defaults()
        self.memory.reset()
        self.nonvolatile.sync_objects()
        self.layout = {RX: Layout(), TX: Layout()}
        if self.io is not None:
            return  # an I/O slave: no CiA-402 model, no units, no plant
        self.cia = Cia402(enable_needs_op=self.behaviour.enable_needs_op,
                          supply_bit_always=self.behaviour.supply_bit_always)
        self.motion.reset()
        self.limit_active = False
        self.limit_switches = (False, False)  # (negative, positive) inputs, set_limit_switches()
        self.homing_warning = False  # Technosoft statusword bit 7 (homing start ignored)
        self.units = units_for(self.behaviour.units, self._read_int, revision=d.revision,
                             has_210f=0x210F in d.dictionary, cycle_s=self.cycle_time())
        self.units.version = lambda: self.objects.store.version  # the store in place (an aborted CA puts another)
        if not self.behaviour.mode_display_on_enable and (0x6061, 0) in entries:
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
        if params is None:
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
            raw = self._read_int(index, 0) if (index, 0) in self.objects.entries else None
            if raw:
                limit = min(limit, abs(raw) / 1000 * plant.params.rated_torque)
        plant.torque_limit = limit

    def set_plant(self, plant: PlantParams | Literal["ideal"] | None = None) -> None:
        """Put the drive on another plant (None: the family's default; ``"ideal"``: the exact tracker). The axis
        keeps its position; the plant starts at rest on the demand."""
        self._axis("a plant")
        self._plant_params = self._params_of(plant)
        self._new_plant()
        self._refresh_inputs()

    def _params_of(self, plant: PlantParams | Literal["ideal"] | None) -> PlantParams | None:
        if plant == "ideal":
            return None
        return plant if isinstance(plant, PlantParams) else self.family_part.default_plant

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
            e = self.objects.entries.get((0x1018, sub))
            if e is not None and e.default is None and e.byte_size == 4:
                self.objects.store[(0x1018, sub)] = value.to_bytes(4, "little")

    # ------------------------------------------------------------------------------------------
    # SlaveTarget
    # ------------------------------------------------------------------------------------------
    def identity(self) -> Identity:
        return self.device.identity

    # ------------------------------------------------------------------------------------------
    # the parts' public API, and the drive's shared state as the tests and tools read it
    # ------------------------------------------------------------------------------------------
    @property
    def _store(self) -> Store:
        return self.objects.store

    @_store.setter
    def _store(self, store: Store) -> None:
        self.objects.store = store

    @property
    def _entries(self) -> dict[tuple[int, int], Entry]:
        return self.objects.entries

    def value(self, index: int, sub: int = 0) -> Any:
        """The decoded value of an entry (no SDO rules, no side effects): for tests and inspection."""
        return self.objects.value(index, sub)

    @property
    def events(self) -> list[Event]:
        return self.event_log.events

    @property
    def emergencies(self) -> list[Emergency]:
        return self.event_log.emergencies

    @property
    def record_events(self) -> bool:
        return self.event_log.record_events

    @record_events.setter
    def record_events(self, on: bool) -> None:
        self.event_log.record_events = on

    def emcy(self, code: int, data: bytes = b"") -> Emergency:
        """Send an emergency message (and log it). Also sets 603Fh/1001h where the drive has them."""
        return self.event_log.emcy(code, data)

    # SDO access
    def sdo_upload(self, index: int, subindex: int, complete_access: bool = False, size: int | None = None) -> bytes:
        """:meth:`.sdo.SdoServer.sdo_upload`."""
        return self.sdo.sdo_upload(index, subindex, complete_access, size)

    def sdo_download(self, index: int, subindex: int, data: bytes, complete_access: bool = False,
                     expect_reply: bool = True) -> None:
        """:meth:`.sdo.SdoServer.sdo_download`."""
        self.sdo.sdo_download(index, subindex, data, complete_access, expect_reply)

    def check_download(self, index: int, subindex: int, complete_access: bool = False) -> None:
        """:meth:`.sdo.SdoServer.check_download`."""
        self.sdo.check_download(index, subindex, complete_access)

    def _upload(self, index: int, sub: int) -> bytes:
        """One entry's upload without the mailbox's logging (the mailbox's segmented transfer reads through it)."""
        return self.sdo._upload(index, sub)

    def _download(self, index: int, sub: int, data: bytes) -> bool:
        return self.sdo._download(index, sub, data)

    # PDO configuration
    def _assigned(self, d: Direction) -> list[int]:
        return self.pdo._assigned(d)

    def _pdo_entries(self, d: Direction, pdo: int) -> Any:
        return self.pdo._pdo_entries(d, pdo)

    # process data
    def process_image_sizes(self) -> tuple[int, int]:
        """(output bytes, input bytes) of the current layout (valid from SAFE-OP on)."""
        return self.process_data.process_image_sizes()

    def exchange(self, outputs: bytes) -> bytes:
        """:meth:`.process_data.ProcessData.exchange`: one cycle."""
        return self.process_data.exchange(outputs)

    def _pack_inputs(self) -> bytes:
        return self.process_data._pack_inputs()

    @property
    def _quiet(self) -> tuple[bytes, tuple[object, ...] | None, bytes] | None:
        return self.process_data._quiet

    @_quiet.setter
    def _quiet(self, quiet: tuple[bytes, tuple[object, ...] | None, bytes] | None) -> None:
        self.process_data._quiet = quiet

    # ESM
    def state(self) -> EcState:
        return self.esm

    def request_state(self, state: EcState) -> None:
        """:meth:`.esm.StateMachine.request_state`."""
        self.state_machine.request_state(state)

    def dc_active(self) -> bool:
        return self.state_machine.dc_active()

    def configure_dc(self, assign_activate: int, sync0_cycle_ns: int = 0, sync0_shift_ns: int = 0) -> None:
        """:meth:`.esm.StateMachine.configure_dc`."""
        self.state_machine.configure_dc(assign_activate, sync0_cycle_ns, sync0_shift_ns)

    @property
    def dc(self) -> tuple[int, int]:
        """(DC activation, SYNC0 cycle ns) as the master configured them."""
        return self.state_machine.dc

    @property
    def dc_shift_ns(self) -> int:
        return self.state_machine.dc_shift_ns

    # CiA-402 and motion
    def cycle_time(self) -> Fraction:
        """The process-data cycle in seconds: 60C2h (sub1 × 10^sub2) where present, else 1 ms, for a drive and an
        I/O slave alike (:meth:`.core.ObjectStore.cycle`)."""
        return self.objects.cycle()[0]

    def cycle_ns(self) -> int:
        """:meth:`cycle_time` in whole nanoseconds, at least 1 (what ``sim serve`` paces the slave by)."""
        return self.objects.cycle()[1]

    def mode(self) -> int:
        """The mode the drive runs (6061h, else 6060h)."""
        return self._axis("a mode of operation").mode()

    def step(self, cycles: int = 1) -> None:
        """Advance the motion model by ``cycles`` process-data cycles (see :meth:`cycle_time`); an I/O slave has
        nothing to advance (time passing changes none of its objects)."""
        if self.io is None:
            self.motion.step(cycles)

    @property
    def internal_position(self) -> int:
        """Position in the drive's internal units (increments), truncated as the drive stores it."""
        return self._axis("a position").internal_position

    @property
    def internal_velocity(self) -> int:
        """Velocity in internal units (Technosoft: 16.16 increments per slow-loop sample)."""
        return self._axis("a velocity").internal_velocity

    @property
    def modes(self) -> ModeParts:
        """The mode parts of the motion part (vl, PP set-points, PV windows, torque, interpolated position)."""
        return self._axis("the CiA-402 modes").modes

    @property
    def cia402_state(self) -> State:
        self._axis("a CiA-402 state")
        return self.cia.state

    # the I/O application
    def set_inputs(self, values: Mapping[tuple[int, int], int]) -> None:
        """:meth:`.io_app.IoApplication.set_inputs`: an I/O slave's input objects, by (index, sub) (a drive's
        inputs are its actual values: :meth:`set_limit_switches`, :meth:`set_load_torque` … act on them)."""
        if self.io is None:
            raise TargetError(f"{self.device.type_name or self.device.name or 'drive'} is a CiA-402 drive: its "
                              "inputs are its actual values (set limit switches, a load torque or an obstacle)")
        self.io.set_inputs(values)

    def process_values(self, d: Direction) -> dict[tuple[int, int], int]:
        """The mapped objects of the process image in direction ``d`` by (index, sub), each its mapped bits as an
        unsigned integer (RX: the outputs as the master last wrote them; TX: the inputs)."""
        return mapped_values(self, d)

    # faults and inputs (a drive's; an I/O slave has none but losing its communication)
    def _faults(self, what: str) -> Injection:
        self._axis(what)
        return self.injection

    def motion_error(self, bit: int) -> None:
        self._faults("a motion error").motion_error(bit)

    def motion_errors(self) -> int:
        return self._faults("a motion error register").motion_errors()

    def fault_reset(self) -> None:
        self._faults("a fault reset").fault_reset()

    def inject_fault(self, code: int, data: bytes = b"") -> None:
        """:meth:`.injection.Injection.inject_fault`."""
        self._faults(f"fault 0x{code:04X}").inject_fault(code, data)

    def lose_communication(self) -> None:
        """:meth:`.injection.Injection.lose_communication` (an I/O slave: its ESM drops to SAFE-OP, nothing else)."""
        if self.io is None:
            self.injection.lose_communication()
        else:
            self.state_machine.watchdog()

    def set_motor_supply(self, present: bool) -> None:
        """:meth:`.injection.Injection.set_motor_supply`."""
        self._faults("a motor supply").set_motor_supply(present)

    def option_end_state(self, index: int, option: int, default: str) -> str:
        return self._faults("an option code").option_end_state(index, option, default)

    def set_limit_switches(self, *, negative: bool = False, positive: bool = False) -> None:
        """:meth:`.injection.Injection.set_limit_switches`."""
        self._faults("limit switches").set_limit_switches(negative=negative, positive=positive)

    def set_load_torque(self, torque: float) -> None:
        """:meth:`.injection.Injection.set_load_torque`."""
        self._faults("a load torque").set_load_torque(torque)

    def set_obstacle(self, position: int | None) -> None:
        """:meth:`.injection.Injection.set_obstacle`."""
        self._faults("an obstacle").set_obstacle(position)

    def inject_hdt_alarm(self, alarm: int, code: int) -> None:
        """:meth:`.injection.Injection.inject_hdt_alarm`."""
        self._faults("an HDT alarm").inject_hdt_alarm(alarm, code)

    def inject_trip(self, trip: int) -> None:
        """:meth:`.injection.Injection.inject_trip`."""
        self._faults("a trip").inject_trip(trip)

    # the family
    def set_encoder_resolution(self, increments: int, revolutions: int = 1) -> None:
        """:meth:`.family.Family.set_encoder_resolution`."""
        self._axis("an encoder resolution")
        self.family_part.set_encoder_resolution(increments, revolutions)

    # memory
    def reset(self) -> None:
        """:meth:`.memory.Memory.reset`: 2080h, the drive (not its EtherCAT interface) restarts."""
        self.nonvolatile.reset()

    def power_cycle(self) -> None:
        """Switch the drive off and on: ESM back to INIT, RAM lost, EEPROM kept."""
        self.nonvolatile.power_cycle()

    def eeprom_words(self, start: int, count: int) -> list[int]:
        return self.nonvolatile.eeprom_words(start, count)

    def foe_accepts(self, name: str, password: int) -> bool:
        """:meth:`.memory.Memory.foe_accepts`."""
        return self.nonvolatile.foe_accepts(name, password)

    def foe_write(self, name: str, data: bytes, password: int = 0) -> None:
        """:meth:`.memory.Memory.foe_write`."""
        self.nonvolatile.foe_write(name, data, password)
