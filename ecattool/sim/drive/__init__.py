"""The drive application of the simulator: what a drive does behind its EtherCAT interface, one concept per
module, combined in :class:`Drive` (the in-process API; the virtual slaves on the wire serve the same object).

* :mod:`.core` — the shared state: object store, event log, emergencies, refused state changes;
* :mod:`.sdo` — the SDO server side of the object dictionary (access, length, range, complete access);
* :mod:`.pdo` — PDO mapping and assignment objects and their rules;
* :mod:`.process_data` — the SAFE-OP check that yields the process image, the cyclic exchange;
* :mod:`.esm` — the EtherCAT state machine, the AL status codes of its refusals, DC settings;
* :mod:`.motion` and :mod:`.halt_homing` — CiA-402 device control, the motion model, halt and homing;
* :mod:`.injection` — faults, trips, alarms, lost communication, limit-switch inputs;
* :mod:`.family` and :mod:`.behaviour` — where the families differ (object handlers; choices as data);
* :mod:`.memory` — EEPROM objects, reset, power loss, FoE;
* :mod:`.facade` — :class:`Drive`, construction and power-on.
"""

from ecattool.sim.drive.behaviour import BEHAVIOURS, CT_TRIP_CODES, Behaviour
from ecattool.sim.drive.core import Emergency, Event
from ecattool.sim.drive.esm import TRANSITIONS
from ecattool.sim.drive.facade import Drive
from ecattool.sim.drive.memory import FoeError

__all__ = [
    "BEHAVIOURS", "Behaviour", "CT_TRIP_CODES", "Drive", "Emergency", "Event", "FoeError", "TRANSITIONS",
]
