"""ESI (EtherCAT Slave Information) files → the device model.

Public API::

    load(path) -> EsiFile                       # every device, module, PDO, SM, DC, EEPROM, dictionary
    load_bytes(data, source) -> EsiFile
    select(esi_or_devices, selector=None, policy="exact") -> Device
    load_device(path, selector=None, policy="exact") -> Device
    validate(path, schema_dir=None) -> list[Finding]
    check_structure(esi) -> list[Finding]

Selectors: a type name (``EL1008``), ``product[:revision]`` in any number notation (``#x03f03052:0x00110000``,
``0x03f03052``, decimal), ``vendor:product:revision``, or a list index (``0``). Policies: ``exact``,
``newest-not-newer``, ``newest``.
"""

from __future__ import annotations

from pathlib import Path

from ecattool.esi.checks import check_structure
from ecattool.esi.model import Device, EsiFile
from ecattool.esi.reader import load
from ecattool.esi.reader import load_bytes as _load_bytes
from ecattool.esi.select import POLICIES, select
from ecattool.esi.validate import materialize, validate


def load_bytes(data: bytes, source: str = "<bytes>", base_dir: str | Path | None = None) -> EsiFile:
    """Read an ESI document from bytes; ``source`` names it in locations, ``base_dir`` resolves referenced files."""
    return _load_bytes(data, source, base_dir)


def load_device(path: str | Path, selector: str | None = None, policy: str = "exact") -> Device:
    """Load ``path`` and select one device (see :func:`select`)."""
    return select(load(path), selector, policy)


__all__ = ["load", "load_bytes", "select", "load_device", "validate", "check_structure", "materialize", "POLICIES",
           "Device", "EsiFile"]
