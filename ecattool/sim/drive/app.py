"""The drive as its parts see it: :class:`DriveApp`, the state the parts share and what they call on each other,
as a protocol :class:`~ecattool.sim.drive.facade.Drive` satisfies.

A part is given the drive (the shared state a power-on or a reset renews: the store's values, the CiA-402 model, the
plant ...) and calls the other parts through it, never through a base class. The protocol names the other parts
only by the few methods a part calls on them, so this module imports no part and every part imports it: core <-
app <- parts <- facade, no cycle (tests/test_layering.py counts type-only imports too).
"""

from __future__ import annotations

from collections.abc import Callable
from fractions import Fraction
from typing import Any, Protocol

from ecattool.esi.model import Device, Direction
from ecattool.od.model import EcState
from ecattool.profiles.rules import FamilyRules
from ecattool.sim import eeprom as ee
from ecattool.sim.cia402 import Cia402, State
from ecattool.sim.drive.behaviour import Behaviour
from ecattool.sim.drive.core import Emergency, EventLog, Layout, ObjectStore
from ecattool.sim.drive.plant import Plant
from ecattool.sim.drive.supervision_state import Supervision
from ecattool.sim.faults import Faults
from ecattool.sim.units import Units


class FamilyData(Protocol):
    """What the parts read of the family part (:class:`~.family.Family`)."""

    @property
    def behaviour(self) -> Behaviour: ...

    @property
    def homing_current(self) -> frozenset[int]: ...

    @property
    def homing_search(self) -> frozenset[int] | None: ...

    def esm_effects(self, previous: EcState, state: EcState) -> None: ...


class ProcessImage(Protocol):
    """What the ESM calls on the process data part (:class:`~.process_data.ProcessData`)."""

    def check_sm(self, d: Direction) -> Layout: ...


class Power(Protocol):
    """What the SDO and process data parts call on the memory part (:class:`~.memory.Memory`)."""

    def power_loss(self) -> None: ...


class Esm(Protocol):
    """What the other parts call on the ESM part (:class:`~.esm.StateMachine`)."""

    def refuse(self, state: EcState, code: int, why: str) -> None: ...

    def fall_to_safeop(self, code: int, why: str) -> None: ...

    def watchdog(self) -> None: ...


class Stepper(Protocol):
    """What the process data part calls on the motion part (:class:`~.motion.Motion`)."""

    def step(self, cycles: int = 1) -> None: ...

    def modes_snapshot(self) -> tuple[object, ...]: ...


class DriveApp(Protocol):
    """The drive as its parts and the helpers of the motion (halt and homing, the mode parts, the plant's step,
    the supervision) see it."""

    # -- set at construction
    device: Device
    rules: FamilyRules
    family: str
    behaviour: Behaviour
    position: int
    strict_pdo_length: bool
    faults: Faults
    memory: ee.Memory
    homing_search_s: Fraction
    objects: ObjectStore
    event_log: EventLog
    _pdo_known: dict[Direction, set[tuple[int, int, int]]]
    _fixed: set[int]
    _pdo_only_set: frozenset[int]
    _read_only_set: frozenset[int]
    _handlers_down: dict[int, Callable[[int, bytes, int | None], bool | None]]
    _handlers_up: dict[int, Callable[[int], bytes]]
    _after_write: dict[int, Callable[[int, int | None], None]]
    # -- the parts' methods every part calls, bound at construction
    _read_int: Callable[[int, int], int | None]
    _put: Callable[[int, int, int], None]
    _put_all: Callable[[tuple[tuple[int, int], ...], tuple[int, ...]], None]
    _log: Callable[..., None]
    _refresh_inputs: Callable[..., None]
    _cia_moves: Callable[[list[tuple[State, State]], str], None]
    _home_offset: Callable[[], int]
    _user_position: Callable[[], int]
    # -- renewed at power-on / reset
    esm: EcState
    layout: dict[Direction, Layout]
    cia: Cia402
    limit_active: bool
    limit_switches: tuple[bool, bool]
    homing_warning: bool
    has_cia402: bool
    units: Units
    plant: Plant | None
    supervision: Supervision
    _demand_before: tuple[int, int]
    _polarity_cache: tuple[int, int, tuple[int, int]]

    # -- the other parts, by what the parts call on them
    @property
    def family_part(self) -> FamilyData: ...

    @property
    def process_data(self) -> ProcessImage: ...

    @property
    def nonvolatile(self) -> Power: ...

    @property
    def state_machine(self) -> Esm: ...

    @property
    def motion(self) -> Stepper: ...

    @property
    def record_events(self) -> bool: ...

    @property
    def emergencies(self) -> list[Emergency]: ...

    def mode(self) -> int: ...

    def step(self, cycles: int = 1) -> None: ...

    def cycle_time(self) -> Fraction: ...

    def dc_active(self) -> bool: ...

    def emcy(self, code: int, data: bytes = b"") -> Emergency: ...

    def inject_fault(self, code: int, data: bytes = b"") -> None: ...

    def option_end_state(self, index: int, option: int, default: str) -> str: ...

    def motion_error(self, bit: int) -> None: ...

    def motion_errors(self) -> int: ...

    def fault_reset(self) -> None: ...

    def _power_on(self) -> None: ...

    def _reset_application(self) -> None: ...

    def value(self, index: int, sub: int = 0) -> Any: ...
