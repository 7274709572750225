"""Reading and checking a live bus: the slaves behind a master (simulator, pysoem, KickCAT) scanned, their objects
read and written typed by a dictionary, their SII read and written with checks, and a project audited against
what the drives hold (docs/at-the-machine.md).

The names below are imported on first use: ``sdo read`` of one object needs the live bus and the object access,
not the audit, the scan or the library (issue 35 item 5: a whole process at most 1.5x a bare pysoem script)."""

from __future__ import annotations

import importlib
import sys
import types
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from ecattool.online.audit import AuditReport, Drift, audit
    from ecattool.online.library import Library, Match
    from ecattool.online.live import LiveBus, LiveSlave, Unsupported, sim_bus
    from ecattool.online.scan import ScannedSlave, scan
    from ecattool.online.targets import open_bus

#: each public name and the module that defines it
_WHERE = {"AuditReport": "audit", "Drift": "audit", "audit": "audit", "Library": "library", "Match": "library",
          "LiveBus": "live", "LiveSlave": "live", "Unsupported": "live", "sim_bus": "live", "ScannedSlave": "scan",
          "scan": "scan", "open_bus": "targets"}


def __getattr__(name: str) -> Any:
    module = _WHERE.get(name)
    if module is None:
        raise AttributeError(f"module 'ecattool.online' has no attribute {name!r}")
    value = getattr(importlib.import_module(f"ecattool.online.{module}"), name)
    globals()[name] = value
    return value


class _Package(types.ModuleType):
    """The package's ``audit`` and ``scan`` are the functions (as they were when this file imported them), not the
    submodules of the same names that the import system binds here when it loads them."""

    def __setattr__(self, name: str, value: Any) -> None:
        if name in ("audit", "scan") and isinstance(value, types.ModuleType):
            return
        super().__setattr__(name, value)


sys.modules[__name__].__class__ = _Package


__all__ = ["AuditReport", "Drift", "Library", "LiveBus", "LiveSlave", "Match", "ScannedSlave", "Unsupported",
           "audit", "open_bus", "scan", "sim_bus"]
