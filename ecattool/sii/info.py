"""A plain-data description of an image (``sii info --json``)."""

from __future__ import annotations

from typing import Any

from ecattool.sii.checks import category_offsets
from ecattool.sii.model import (
    FMMU_USAGE,
    PDO_FLAGS,
    GeneralCategory,
    RawCategory,
    SiiImage,
    SiiPdo,
    category_body,
    category_name,
)

COE_DETAILS = {"sdo": 0x01, "sdo_info": 0x02, "pdo_assign": 0x04, "pdo_config": 0x08, "pdo_upload": 0x10,
               "complete_access": 0x20}
GENERAL_FLAGS = {"enable_safeop": 0x01, "enable_not_lrw": 0x02, "mbox_data_link_layer": 0x04,
                 "ident_al_status": 0x08, "ident_physical_memory": 0x10}
PORT_TYPES = {0: "none", 1: "MII", 2: "reserved", 3: "EBUS", 4: "fast hot connect"}


def _bits(value: int, names: dict[str, int]) -> list[str]:
    return [n for n, b in names.items() if value & b]


def _pdo(image: SiiImage, p: SiiPdo) -> dict[str, Any]:
    return {
        "index": p.index, "name": image.string(p.name_idx), "sm": p.sm, "dc_sync": p.dc_sync, "flags": p.flags,
        "flag_names": _bits(p.flags, PDO_FLAGS), "bit_size": sum(e.bit_len for e in p.entries),
        "entries": [{"index": e.index, "subindex": e.subindex, "name": image.string(e.name_idx),
                     "data_type": e.data_type, "bit_len": e.bit_len, "flags": e.flags} for e in p.entries],
    }


def general_dict(image: SiiImage, g: GeneralCategory) -> dict[str, Any]:
    ports = [PORT_TYPES.get((g.physical_port >> (4 * i)) & 0xF, "?") for i in range(4)]
    return {
        "group": image.string(g.group_idx), "image": image.string(g.image_idx), "order": image.string(g.order_idx),
        "name": image.string(g.name_idx), "group_name": image.string(g.group_name_idx),
        "coe_details": g.coe_details, "coe": _bits(g.coe_details, COE_DETAILS), "foe": bool(g.foe_details & 1),
        "eoe": bool(g.eoe_details & 1), "flags": g.flags, "flag_names": _bits(g.flags, GENERAL_FLAGS),
        "current_on_ebus_ma": g.current_on_ebus, "physical_layer": g.physical_layer,
        "physical_port": g.physical_port, "ports": ports, "physical_memory_address": g.physical_memory_address,
    }


def describe(image: SiiImage) -> dict[str, Any]:
    h = image.header
    raw = image.to_bytes()
    cats = []
    for c, off in zip(image.categories, category_offsets(image)):
        entry: dict[str, Any] = {"type": c.cat_type, "name": category_name(c.cat_type),
                                 "words": len(category_body(c)) // 2, "offset": off}
        if isinstance(c, RawCategory):
            entry["data"] = c.data.hex()
            if c.problem:
                entry["problem"] = c.problem
        cats.append(entry)
    g = image.general
    return {
        "source": image.source,
        "vendor_id": h.vendor_id, "product_code": h.product_code, "revision": h.revision, "serial": h.serial,
        "station_alias": h.station_alias, "checksum": h.checksum & 0xFF, "crc_ok": image.crc_ok,
        "pdi_control": h.pdi_control, "pdi_config": h.pdi_config, "sync_impulse_len": h.sync_impulse_len,
        "pdi_config2": h.pdi_config2, "config_data": raw[:14].hex(),
        "bootstrap": {"rx_offset": h.bootstrap_rx_offset, "rx_size": h.bootstrap_rx_size,
                      "tx_offset": h.bootstrap_tx_offset, "tx_size": h.bootstrap_tx_size},
        "mailbox": {"rx_offset": h.std_rx_offset, "rx_size": h.std_rx_size,
                    "tx_offset": h.std_tx_offset, "tx_size": h.std_tx_size},
        "mailbox_protocols": h.mailbox_protocols, "protocols": h.protocols,
        "size_word": h.size_word, "eeprom_bytes": h.eeprom_bytes, "version": h.version,
        "image_bytes": len(raw), "end_marker": image.end_marker,
        "categories": cats,
        "strings": image.strings,
        "general": general_dict(image, g) if g else None,
        "fmmus": [FMMU_USAGE.get(u, f"0x{u:02X}") or "unused" for u in image.fmmus],
        "sync_managers": [{**s.as_dict(), "kind": s.kind} for s in image.sync_managers],
        "tx_pdos": [_pdo(image, p) for p in image.tx_pdos],
        "rx_pdos": [_pdo(image, p) for p in image.rx_pdos],
        "dc_opmodes": [{**{k: v for k, v in o.as_dict().items() if k != "reserved"},
                        "name": image.string(o.name_idx), "desc": image.string(o.desc_idx)}
                       for o in image.dc_opmodes],
    }
