"""A slave's state as found before a master reset the bus (``ecattool.online.bus_state`` reads it with raw frames):
a record of its own, which a command reading through a held bus (``ecattool.online.held``) receives from the holder
without loading the raw frame code."""

from __future__ import annotations

from typing import Any

from ecattool.abort import AlStatus
from ecattool.od.model import EcState
from ecattool.record import FrozenRecord, set_field

_STATES = {0x01: EcState.INIT, 0x02: EcState.PREOP, 0x03: EcState.BOOT, 0x04: EcState.SAFEOP, 0x08: EcState.OP}
RUNNING = (EcState.SAFEOP, EcState.OP)


class Found(FrozenRecord):
    """A slave's AL state as found before the bus was reset (``state`` None: an AL status that names none), and
    its AL status code (0x0134). It pickles (a holder sends a list of them to each command: FrozenRecord's state)."""

    __slots__ = ("position", "al_status", "al_status_code", "assign_activate", "sync0_cycle_ns", "sync1_cycle_ns",
                 "sii")
    position: int
    al_status: int
    al_status_code: int
    #: the slave's DC activation as found (ESC 0x0980-0x0981: the ESI's AssignActivate word; 0: no SYNC
    #: signal) and its SYNC0/SYNC1 cycle times (0x09A0, 0x09A4, ns); None where they were not read
    assign_activate: int | None
    sync0_cycle_ns: int | None
    sync1_cycle_ns: int | None
    #: the slave's SII image (from word 0 to the end of the category list), read through the ESC's EEPROM
    #: interface before the master opened, where asked (:func:`ecattool.online.bus_state.read_states` ``sii``:
    #: KickCAT binds no SII access); left out of the repr
    sii: bytes | None

    def __init__(self, position: int, al_status: int, al_status_code: int = AlStatus.NO_ERROR.value,
                 assign_activate: int | None = None, sync0_cycle_ns: int | None = None,
                 sync1_cycle_ns: int | None = None, sii: bytes | None = None) -> None:
        set_field(self, "position", position)
        set_field(self, "al_status", al_status)
        set_field(self, "al_status_code", al_status_code)
        set_field(self, "assign_activate", assign_activate)
        set_field(self, "sync0_cycle_ns", sync0_cycle_ns)
        set_field(self, "sync1_cycle_ns", sync1_cycle_ns)
        set_field(self, "sii", sii)

    def replace(self, **changes: Any) -> Found:
        """A copy with ``changes`` (field name → value), as ``dataclasses.replace`` made one."""
        return Found(**{**{n: getattr(self, n) for n in self._fields}, **changes})

    def __repr__(self) -> str:  # without the SII image (hundreds of bytes), as the dataclass's field(repr=False)
        body = ", ".join(f"{n}={getattr(self, n)!r}" for n in self._fields if n != "sii")
        return f"Found({body})"

    @property
    def error(self) -> bool:
        """The AL status's error indication (bit 4): the slave refused a state change or left a state by itself."""
        return bool(self.al_status & 0x10)

    @property
    def state(self) -> EcState | None:
        return _STATES.get(self.al_status & 0x0F)

    def __str__(self) -> str:
        name = self.state.value if self.state is not None else f"AL status 0x{self.al_status:02X}"
        return f"slave {self.position} ({name}{', error' if self.al_status & 0x10 else ''})"
