"""The drive application of the simulator: what a drive does behind its EtherCAT interface, one concern per part,
composed in :class:`Drive` (the in-process API; the virtual slaves on the wire serve the same object). The parts are
objects the drive builds and wires together at construction; none inherits another.

* :mod:`.core` — the object store part and the event log with the emergencies; the store, events, process image;
* :mod:`.family` and :mod:`.behaviour` — the family part, chosen once from the family's data (rules, behaviour as
  data, homing tables, default plant), with its object handlers and ESM reactions;
* :mod:`.sdo` — SDO access to the object dictionary (access, length, range, complete access);
* :mod:`.pdo` — PDO mapping and assignment objects and their rules;
* :mod:`.process_data` — the SAFE-OP check that yields the process image, the cyclic exchange;
* :mod:`.esm` — the EtherCAT state machine, the AL status codes of its refusals, DC settings;
* :mod:`.motion` and :mod:`.halt_homing` — CiA-402 device control, the motion model, halt and homing; the mode
  parts (:mod:`.mode_parts`), the plant (:mod:`.plant`, :mod:`.plant_step`) and supervision (:mod:`.supervision`);
* :mod:`.injection` — faults, trips, alarms, lost communication, limit-switch inputs;
* :mod:`.io_app` — the I/O application of a slave without the CiA-402 objects (a terminal, a coupler), which it
  holds instead of the motion and fault parts: its process data is its object store as mapped;
* :mod:`.memory` — EEPROM objects, reset, power loss, FoE;
* :mod:`.facade` — :class:`Drive`, the parts wired together, construction and power-on.
"""

from ecattool.sim.drive.behaviour import BEHAVIOURS, CT_TRIP_CODES, Behaviour
from ecattool.sim.drive.core import Emergency, Event
from ecattool.sim.drive.esm import TRANSITIONS
from ecattool.sim.drive.facade import Drive
from ecattool.sim.drive.memory import FoeError

__all__ = [
    "BEHAVIOURS", "Behaviour", "CT_TRIP_CODES", "Drive", "Emergency", "Event", "FoeError", "TRANSITIONS",
]
