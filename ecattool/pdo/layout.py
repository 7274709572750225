"""The process image of a mapping: per sync manager, every entry with its byte.bit offset, size, name, type."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from ecattool.esi.model import Device, Direction
from ecattool.pdo.model import Mapping, without_virtual


@dataclass(frozen=True, slots=True)
class ImageEntry:
    pdo: int
    index: int
    subindex: int
    bit_offset: int  # from the start of the sync manager's image
    bit_len: int
    name: str = ""
    type_name: str = ""

    @property
    def byte(self) -> int:
        return self.bit_offset // 8

    @property
    def bit(self) -> int:
        return self.bit_offset % 8

    @property
    def offset(self) -> str:
        """``byte.bit`` as PLC programmers write it (``2.0``, ``6.3``)."""
        return f"{self.byte}.{self.bit}"

    @property
    def is_gap(self) -> bool:
        return self.index == 0

    def to_json(self) -> dict[str, Any]:
        return {
            "pdo": f"0x{self.pdo:04X}",
            "index": f"0x{self.index:04X}",
            "subindex": self.subindex,
            "offset": self.offset,
            "byte": self.byte,
            "bit": self.bit,
            "bits": self.bit_len,
            "name": self.name,
            "type": self.type_name,
        }


@dataclass(slots=True)
class SmImage:
    direction: Direction
    sm: int | None
    start_address: int | None
    pdos: list[int] = field(default_factory=list)
    entries: list[ImageEntry] = field(default_factory=list)

    @property
    def bit_size(self) -> int:
        return sum(e.bit_len for e in self.entries)

    @property
    def byte_size(self) -> int:
        return (self.bit_size + 7) // 8

    def to_json(self) -> dict[str, Any]:
        return {
            "direction": self.direction.value,
            "sm": self.sm,
            "start_address": None if self.start_address is None else f"0x{self.start_address:04X}",
            "assign_index": f"0x{self.direction.assign_index:04X}",
            "pdos": [f"0x{p:04X}" for p in self.pdos],
            "bits": self.bit_size,
            "bytes": self.byte_size,
            "entries": [e.to_json() for e in self.entries],
        }


@dataclass(slots=True)
class Layout:
    outputs: SmImage
    inputs: SmImage

    def image(self, direction: Direction) -> SmImage:
        return self.outputs if direction is Direction.RX else self.inputs

    def to_json(self) -> dict[str, Any]:
        return {"outputs": self.outputs.to_json(), "inputs": self.inputs.to_json()}


def _type_name(device: Device, index: int, sub: int, fallback: str) -> str:
    entry = device.dictionary.entry(index, sub)
    if entry is not None and entry.type_name:
        return entry.type_name
    return fallback


def layout(device: Device, mapping: Mapping) -> Layout:
    """Lay out the process image of ``mapping`` on ``device`` (RX → outputs/SM2, TX → inputs/SM3); virtual PDOs
    (ESC registers, :func:`ecattool.pdo.model.without_virtual`) are no part of a sync manager's image."""
    mapping = without_virtual(device, mapping)[0]
    images: dict[Direction, SmImage] = {}
    for direction in Direction:
        sm = device.process_sm(direction)
        img = SmImage(direction, sm.number if sm else None, sm.start_address if sm else None)
        offset = 0
        for pdo in mapping.pdos(direction):
            img.pdos.append(pdo.index)
            for e in pdo.entries:
                name = "gap" if e.is_gap else e.name
                type_name = "" if e.is_gap else _type_name(device, e.index, e.subindex, e.data_type)
                img.entries.append(ImageEntry(pdo.index, e.index, e.subindex, offset, e.bit_len, name, type_name))
                offset += e.bit_len
        images[direction] = img
    return Layout(images[Direction.RX], images[Direction.TX])
