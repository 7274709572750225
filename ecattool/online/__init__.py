"""Reading and checking a live bus: the slaves behind a master (simulator, pysoem, KickCAT) scanned, their objects
read and written typed by a dictionary, their SII read and written with checks, and a project audited against
what the drives hold (docs/at-the-machine.md)."""

from ecattool.online.audit import AuditReport, Drift, audit
from ecattool.online.library import Library, Match
from ecattool.online.live import LiveBus, LiveSlave, Unsupported, sim_bus
from ecattool.online.targets import open_bus
from ecattool.online.scan import ScannedSlave, scan

__all__ = ["AuditReport", "Drift", "Library", "LiveBus", "LiveSlave", "Match", "ScannedSlave", "Unsupported",
           "audit", "open_bus", "scan", "sim_bus"]
