"""A mapping object that contradicts its PDO element (issue 35 item 7): an ESI whose dictionary gives a mapping
object (1600h-17FFh, 1A00h-1BFFh) its own complete default (the count and every entry it counts, as DefaultData)
that lays out other entries than the ``<RxPdo>``/``<TxPdo>`` element of the same index (the dictionary's 1600h
says 60B8h at entry 3, the PDO element 60FFh).

The slave powers on with its dictionary: that is what it holds in the object and what every CoE master reads
from it (SOEM's and KickCAT's ``config_map`` read 1C12h/1C13h and the mapping objects). ecattool takes the same
choice everywhere a device's power-on image is drawn or served: the simulator's slave holds the dictionary's
mapping (``sim.drive.pdo``), ``map layout`` draws it (``pdo.power_on_mapping``) and the SII builder describes it in
the PDO categories (a master without CoE lays out its sync managers by them). ``esi validate`` and lint report
the contradiction (``esi-pdo-default-differs``) at the dictionary object's line, naming the PDO element's line;
a project that means the PDO element's entries gives them in ``pdo:`` (commission programs them) and lint's
PRJ027 says so where it keeps the power-on mapping. docs/decisions.md, "An ESI that contradicts itself".

Trailing padding is no difference (an EL6692's 1600h: a gap of 8 bits against an empty PDO element): the same
data (:func:`without_trailing_padding`, the comparison lint's PRJ027 uses).
"""

from __future__ import annotations

from dataclasses import dataclass

from ecattool.errors import Location
from ecattool.esi.model import Device, Direction, Pdo, PdoEntry

#: the CoE mapping objects (ETG.1000.6): only these hold a power-on mapping a master reads
MAPPING_RANGES = {Direction.RX: range(0x1600, 0x1800), Direction.TX: range(0x1A00, 0x1C00)}


def without_trailing_padding(values: list[int]) -> list[int]:
    """Mapping values without the gaps and dummies (index below 20h) at their end: they pad the PDO and carry
    nothing, so a mapping object that differs from the PDO list only by them lays out the same data."""
    out = list(values)
    while out and (out[-1] >> 16) < 0x20:
        out.pop()
    return out


def own_mapping_values(device: Device, index: int) -> list[int] | None:
    """The mapping values the dictionary's own object ``index`` holds at power-on: where the ESI's dictionary
    gives the object (read from the file, not completed from the PDO list) a default count and a default for
    every entry it counts; None where it does not say."""
    obj = device.dictionary.get(index)
    if obj is None or obj.location is None or not obj.location.line:
        return None
    count = obj.entry(0)
    if count is None or not count.default:
        return None
    out = []
    for sub in range(1, int.from_bytes(count.default, "little") + 1):
        e = obj.entry(sub)
        if e is None or not e.default:
            return None
        out.append(int.from_bytes(e.default[:4], "little"))
    return out


@dataclass(frozen=True, slots=True)
class Contradiction:
    """A PDO element and the dictionary's mapping object of the same index that disagree: ``held`` the
    dictionary's mapping values (what the slave powers on with), ``listed`` the PDO element's."""

    pdo: Pdo
    held: list[int]
    listed: list[int]
    location: Location | None  # the dictionary object's

    @property
    def same_image(self) -> bool:
        """Whether both lay out the same bits (only the objects named differ)."""
        return [v & 0xFF for v in self.held] == [v & 0xFF for v in self.listed]


def contradictions(device: Device) -> list[Contradiction]:
    """The PDO elements of ``device`` whose mapping object in its dictionary holds another default mapping
    (beyond trailing padding); a virtual PDO (ESC registers) has no mapping object and is left out."""
    out = []
    for direction, span in MAPPING_RANGES.items():
        for pdo in device.pdos(direction):
            if pdo.index not in span or device.esc_registers(pdo):
                continue
            held = own_mapping_values(device, pdo.index)
            if held is None:
                continue
            listed = [e.mapping_value for e in pdo.entries]
            if without_trailing_padding(held) != without_trailing_padding(listed):
                obj = device.dictionary.get(pdo.index)
                out.append(Contradiction(pdo, held, listed, obj.location if obj is not None else None))
    return out


def power_on_entries(device: Device, pdo: Pdo) -> list[PdoEntry]:
    """The entries ``pdo`` has at power-on: the dictionary's own mapping object where it differs from the PDO
    element (named and typed by the dictionary; trailing padding included, as ``pdo.default_mapping`` and the
    simulator take it: the image the slave has), else the element's."""
    held = own_mapping_values(device, pdo.index) if pdo.index in MAPPING_RANGES[pdo.direction] else None
    if held is None or held == [e.mapping_value for e in pdo.entries]:
        return list(pdo.entries)
    out = []
    for value in held:
        index, sub, bits = value >> 16, (value >> 8) & 0xFF, value & 0xFF
        entry = device.dictionary.entry(index, sub) if index >= 0x20 else None
        name = entry.name if entry is not None else ("" if index >= 0x20 else "gap")
        data_type = entry.type_name if entry is not None and entry.type_name else ""
        out.append(PdoEntry(index, sub, bits, name, data_type))
    return out
