"""What ``ecattool sim show`` tells of a simulated drive: its identity, the family's limits, the PDOs as the drive
holds them after reset (assigned or not, with their entries) and, on request, its dictionary, as plain data
(JSON-ready) for the command to print or render."""

from __future__ import annotations

from typing import Any

from ecattool.esi.model import Direction
from ecattool.sim.drive import Drive


def pdo_rows(drive: Drive) -> list[dict[str, Any]]:
    """Every PDO of the drive's device as the drive holds it now: direction, index, name, whether it is assigned,
    its size in bits and its entries (as 32-bit mapping values)."""
    out = []
    for d in (Direction.RX, Direction.TX):
        assigned = drive._assigned(d)
        for pdo in drive.device.pdos(d):
            entries = drive._pdo_entries(d, pdo.index) or []
            out.append({"direction": d.value, "index": pdo.index, "name": pdo.name, "assigned": pdo.index in assigned,
                        "bits": sum(e.bit_len for e in entries),
                        "entries": [f"0x{e.mapping_value:08X}" for e in entries]})
    return out


def describe_drive(drive: Drive, objects: bool = False) -> dict[str, Any]:
    """The drive's identity, its family's limits and its PDOs (:func:`pdo_rows`); with ``objects`` its dictionary
    too (each object's entries with type, access, PDO mapping and default)."""
    dev, rules = drive.device, drive.rules
    info: dict[str, Any] = {
        "profile": rules.family, "type": dev.type_name, "name": dev.name,
        "vendor_id": dev.vendor_id, "product_code": dev.product_code, "revision": dev.revision,
        "rules": {"max_pdo_bits": rules.max_pdo_bits, "max_pdo_entries": rules.max_pdo_entries,
                  "max_assigned_rx": rules.max_assigned_rx, "max_assigned_tx": rules.max_assigned_tx,
                  "supported_modes": list(rules.supported_modes)},
        "pdos": pdo_rows(drive),
    }
    if objects:
        info["objects"] = [{"index": o.index, "name": o.name, "object_code": o.object_code.value,
                            "entries": [{"subindex": e.subindex, "name": e.name, "type": e.type_name,
                                         "access": e.access.text, "pdo_mapping": e.pdo_mapping,
                                         "default": e.default.hex() if e.default is not None else None}
                                        for e in o]} for o in dev.dictionary]
    return info
