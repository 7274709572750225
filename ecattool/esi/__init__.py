"""ESI (EtherCAT Slave Information) files → the device model.

Public API::

    load(path) -> EsiFile                       # every device, module, PDO, SM, DC, EEPROM, dictionary
                                                # (a CANopen EDS/DCF too: ecattool.esi.eds)
    load(path, lazy=True) -> EsiFile            # same content; devices built when selected or listed
    load_bytes(data, source, lazy=False) -> EsiFile
    select(esi_or_devices, selector=None, policy="exact") -> Device
    load_device(path, selector=None, policy="exact") -> Device   # builds only the selected device
    validate(path, schema_dir=None) -> list[Finding]
    check_structure(esi) -> list[Finding]
    device_findings(esi, device) / file_findings(esi) -> list[Finding]   # reader findings by where they are

Selectors: a type name (``EL1008``), ``product[:revision]`` in any number notation (``#x03f03052:0x00110000``,
``0x03f03052``, decimal), ``vendor:product:revision``, or a list index (``0``). Policies: ``exact``,
``newest-not-newer``, ``newest``.
"""

from __future__ import annotations

import importlib
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ecattool.esi.model import Device, EsiFile
from ecattool.esi.select import POLICIES, select, select_index

if TYPE_CHECKING:
    from ecattool.findings import Finding

# Checks and validation (and their XSD machinery) are imported on first use: reading a file does not need them.
# The wrappers stay bound after the first call (importing the submodule ``validate`` would otherwise leave the
# package attribute ``validate`` pointing at the module).


def _validate_module() -> Any:
    module = importlib.import_module("ecattool.esi.validate")
    globals()["validate"] = _validate  # the import bound the package attribute to the submodule
    return module


def validate(path: str | Path, schema_dir: str | Path | None = None) -> list[Finding]:
    """All findings for one ESI file (see :func:`ecattool.esi.validate.validate`)."""
    return _validate_module().validate(path, schema_dir)  # type: ignore[no-any-return]


def materialize(esi: EsiFile) -> int:
    """Build every (lazily read) dictionary of ``esi``; returns the number of objects."""
    return _validate_module().materialize(esi)  # type: ignore[no-any-return]


def check_structure(esi: EsiFile) -> list[Finding]:
    """Schema-free structural checks of every device in ``esi`` (see :mod:`ecattool.esi.checks`)."""
    from ecattool.esi.checks import check_structure as check

    return check(esi)


_validate = validate


def device_findings(esi: EsiFile, device: Device) -> list[Finding]:
    """The reader findings of ``esi`` located inside ``device``'s element (its lines, in its file)."""
    loc = device.location
    if loc is None or loc.line is None:
        return []
    start, end = loc.line, device.end_line
    return [w for w in esi.warnings
            if w.location is not None and w.location.file == loc.file and w.location.line is not None
            and start <= w.location.line and (end is None or w.location.line < end)]


def file_findings(esi: EsiFile) -> list[Finding]:
    """The reader findings of ``esi`` not inside any of its (loaded) devices: file-level ones, skipped devices."""
    inside = {id(w) for d in esi.devices for w in device_findings(esi, d)}
    return [w for w in esi.warnings if id(w) not in inside]


def _is_eds(data: bytes) -> bool:
    from ecattool.esi.eds import looks_like_eds

    return looks_like_eds(data)


def load(path: str | Path, lazy: bool = False) -> EsiFile:
    """Read an ESI file (EtherCATInfo, EtherCATModule or EtherCATDict root), or a CANopen EDS/DCF file (told
    apart by content: see :mod:`ecattool.esi.eds`); ``lazy`` as in :func:`load_bytes`."""
    import stat

    p = Path(path)
    try:
        regular = stat.S_ISREG(p.stat().st_mode)
    except OSError:
        regular = True  # the reader reports the file error
    if not regular:  # a FIFO or a device is read once: its first bytes cannot be peeked and read again
        from ecattool.fileio import read_bytes
        from ecattool.xmlsafe import MAX_XML_BYTES

        return load_bytes(read_bytes(p, MAX_XML_BYTES), str(p), base_dir=p.parent, lazy=lazy)
    try:
        with open(p, "rb") as fh:
            head = fh.read(4096)
    except OSError:
        head = b""  # the reader reports the file error
    if _is_eds(head):
        from ecattool.esi.eds import load_eds

        return load_eds(p)
    from ecattool.esi.reader import load as read  # on first use: the model alone (a live bus's identity) needs no lxml

    return read(p, lazy)


def load_bytes(data: bytes, source: str = "<bytes>", base_dir: str | Path | None = None,
               lazy: bool = False) -> EsiFile:
    """Read an ESI (or CANopen EDS/DCF) document from bytes; ``source`` names it in locations, ``base_dir``
    resolves referenced files, ``lazy`` builds devices only when selected or listed."""
    if _is_eds(data):
        from ecattool.esi.eds import load_eds_bytes

        return load_eds_bytes(data, source)
    from ecattool.esi.reader import load_bytes as read

    return read(data, source, base_dir, lazy)


def load_device(path: str | Path, selector: str | None = None, policy: str = "exact") -> Device:
    """Load ``path`` and select one device (see :func:`select`); only that device is built."""
    return select(load(path, lazy=True), selector, policy)


__all__ = [
    "POLICIES",
    "Device",
    "EsiFile",
    "check_structure",
    "device_findings",
    "file_findings",
    "load",
    "load_bytes",
    "load_device",
    "materialize",
    "select",
    "select_index",
    "validate",
]
