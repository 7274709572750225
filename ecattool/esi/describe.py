"""ESI devices as plain data (JSON-ready): the summary ``esi devices`` lists per device, and the document
``esi show --json`` prints (identity, PDOs and module PDOs, slots, dictionary, sync managers, DC op modes, init
commands, each as chosen)."""

from __future__ import annotations

from typing import Any

from ecattool.esi.model import Device, InitCmd, Pdo
from ecattool.findings import Finding
from ecattool.od.model import ObjectDictionary


def device_summary(dev: Device, index: int) -> dict[str, Any]:
    """The row of ``dev`` (at ``index`` in its file) that ``esi devices`` lists."""
    return {
        "index": index,
        "type": dev.type_name,
        "name": dev.name,
        "vendor_id": dev.vendor_id,
        "product_code": dev.product_code,
        "revision": dev.revision,
        "group": dev.group_type,
        "rx_pdo_count": len(dev.rx_pdos),
        "tx_pdo_count": len(dev.tx_pdos),
        "object_count": len(dev.dictionary),
        "sm_count": len(dev.sync_managers),
        "protocols": list(dev.mailbox.protocols) if dev.mailbox else [],
        "modules": len(dev.modules),
        "slots": len(dev.slots),
        "line": dev.location.line if dev.location else None,
    }


def pdo_json(p: Pdo) -> dict[str, Any]:
    return {
        "direction": p.direction.value, "index": p.index, "name": p.name, "sm": p.sm, "fixed": p.fixed,
        "mandatory": p.mandatory, "virtual": p.virtual, "excludes": p.excludes, "bit_size": p.bit_size,
        "entries": [{"index": e.index, "subindex": e.subindex, "bit_len": e.bit_len, "name": e.name,
                     "data_type": e.data_type} for e in p.entries],
        "line": p.location.line if p.location else None,
    }


def objects_json(od: ObjectDictionary) -> list[dict[str, Any]]:
    out = []
    for o in od:
        out.append({
            "index": o.index, "name": o.name, "object_code": o.object_code.value, "type": o.type_name,
            "entries": [{"subindex": e.subindex, "name": e.name, "type": e.type_name,
                         "datatype": e.datatype.name if e.datatype else None, "bit_size": e.bit_size,
                         "bit_offset": e.bit_offset, "access": e.access.text, "pdo_mapping": e.pdo_mapping,
                         "default": e.default.hex() if e.default is not None else None, "minimum": e.minimum,
                         "maximum": e.maximum, "enum": {str(k): v for k, v in e.enum.items()},
                         "backup": e.backup, "setting": e.setting} for e in o],
        })
    return out


def sm_json(dev: Device) -> list[dict[str, Any]]:
    return [{"number": s.number, "kind": s.kind, "start_address": s.start_address, "default_size": s.default_size,
             "min_size": s.min_size, "max_size": s.max_size, "control_byte": s.control_byte, "enable": s.enable,
             "enable_byte": s.enable_byte}
            for s in dev.sync_managers]


def dc_json(dev: Device) -> list[dict[str, Any]]:
    keys = ("name", "desc", "assign_activate", "cycle_time_sync0", "cycle_time_sync0_factor", "shift_time_sync0",
            "shift_time_sync0_factor", "cycle_time_sync1", "cycle_time_sync1_factor", "shift_time_sync1",
            "shift_time_sync1_factor")
    return [{k: getattr(m, k) for k in keys} for m in dev.dc_opmodes]


def init_cmds(dev: Device) -> list[InitCmd]:
    return list(dev.mailbox.init_cmds) if dev.mailbox else []


def init_json(dev: Device) -> list[dict[str, Any]]:
    return [{"protocol": c.protocol, "transitions": c.transitions, "index": c.index, "subindex": c.subindex,
             "data": c.data.hex(), "comment": c.comment, "fixed": c.fixed, "complete_access": c.complete_access}
            for c in init_cmds(dev)]


def show_document(dev: Device, index: int, warnings: list[Finding], *, pdos: bool = False, objects: bool = False,
                  sm: bool = False, dc: bool = False, init: bool = False) -> dict[str, Any]:
    """What ``esi show --json`` prints of ``dev``: its summary, ``warnings`` and details, and the sections asked
    for (none asked for: the PDOs, module PDOs, slots and sync managers)."""
    any_section = pdos or objects or sm or dc or init
    data: dict[str, Any] = device_summary(dev, index)
    data["warnings"] = [w.to_json() for w in warnings]
    data.update({"physics": dev.physics, "profile_no": dev.profile_no, "group_name": dev.group_name,
                 "url": dev.url, "ebus_current_ma": dev.ebus_current_ma, "source": dev.source})
    if pdos or not any_section:
        data["pdos"] = [pdo_json(p) for p in (*dev.rx_pdos, *dev.tx_pdos)]
        data["module_pdos"] = [{"type": m.type_name, "ident": m.ident, "name": m.name,
                                "pdos": [pdo_json(p) for p in (*m.rx_pdos, *m.tx_pdos)]} for m in dev.modules]
        data["slots"] = [{"name": s.name, "min_instances": s.min_instances, "max_instances": s.max_instances,
                          "module_idents": s.module_idents, "default_module": s.default_module} for s in dev.slots]
    if objects:
        data["objects"] = objects_json(dev.dictionary)
    if sm or not any_section:
        data["sync_managers"] = sm_json(dev)
    if dc:
        data["dc_opmodes"] = dc_json(dev)
    if init:
        data["init_cmds"] = init_json(dev)
    return data
