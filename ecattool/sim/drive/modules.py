"""Modular devices (ETG.2001 slots): the device as an ESI-configured master starts it, each slot's default
module plugged in."""

from __future__ import annotations

from ecattool.esi.model import Device


def expand_default_modules(device: Device) -> Device:
    """A modular device (ETG.2001 slots) with each slot's default module plugged in: the module PDOs are
    added with the slot's PDO increment, their entries (and the module dictionaries) with the slot's index
    increment, as an ESI-configured master does before it starts the slave."""
    if not device.slots or device.rx_pdos or device.tx_pdos:
        return device
    import copy

    out = copy.deepcopy(device)
    by_ident = {m.ident: m for m in out.modules if m.ident is not None}
    for k, slot in enumerate(out.slots):
        module = by_ident.get(slot.default_module) if slot.default_module is not None else None
        if module is None:
            continue
        for _ in range(max(1, slot.min_instances)):
            idx_inc = (slot.slot_index_increment or 0) * k
            pdo_inc = (slot.slot_pdo_increment or 0) * k
            for obj in module.dictionary:
                moved = copy.deepcopy(obj)
                if 0x6000 <= obj.index <= 0x9FFF:
                    moved.index += idx_inc
                out.dictionary.add(moved)
            for src, dst in ((module.rx_pdos, out.rx_pdos), (module.tx_pdos, out.tx_pdos)):
                for pdo in src:
                    p = copy.deepcopy(pdo)
                    if p.depend_on_slot:
                        p.index += pdo_inc
                        for e in p.entries:
                            if e.index >= 0x2000:
                                e.index += idx_inc
                    dst.append(p)
            break
    return out
