"""The I/O application: what a slave without the CiA-402 objects (a digital or analog terminal, a coupler, a
mailbox-less EJ/EL module) runs behind its EtherCAT interface.

Its process data is its object store as mapped: the outputs the master writes are latched into the mapped
objects (the process data part does that) and held there; the inputs are whatever the objects mapped into the
TxPDOs hold, which a test, a script or the library sets with :meth:`IoApplication.set_inputs`. There is no
motion, no plant, no supervision and no CiA-402 state machine: a cycle is the latch and the input image, nothing
is stepped. The ESM (SM/FMMU checks, the watchdog) is the same part a drive has.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING

from ecattool.errors import TargetError
from ecattool.esi.model import Direction
from ecattool.od.types import Kind
from ecattool.sim.drive.core import RX, TX

if TYPE_CHECKING:
    from ecattool.sim.drive.app import DriveApp


class IoApplication:
    """The application part of an I/O slave (a :class:`~ecattool.sim.drive.facade.Drive` whose dictionary has
    no 6040h/6041h holds it instead of the motion and fault parts)."""

    __slots__ = ("drive",)

    def __init__(self, drive: DriveApp) -> None:
        self.drive = drive

    def refresh(self, mode: int | None = None) -> None:
        """Nothing to refresh: no actual values are computed, the inputs are the objects as they are set."""

    def no_axis(self, what: str) -> TargetError:
        """The one-line error of a call only a CiA-402 axis answers."""
        device = self.drive.device
        return TargetError(f"{device.type_name or device.name or 'slave'} is an I/O slave (no CiA-402 objects "
                           f"6040h/6041h): {what} needs a drive")

    def mappable(self, d: Direction) -> dict[tuple[int, int], int]:
        """(index, sub) -> bits of every object the slave can map in direction ``d`` (dummies left out)."""
        return {(index, sub): bits for index, sub, bits in self.drive._pdo_known.get(d, ()) if index >= 0x20}

    def set_inputs(self, values: Mapping[tuple[int, int], int]) -> None:
        """Set input objects (those the slave maps into its TxPDOs: 6000h:01 of an EL1008 …) to integer values;
        the next input image carries them. All or nothing: an object the slave cannot map as an input, or a
        value that does not fit its bits, is a one-line :class:`TargetError` and nothing is set."""
        drive = self.drive
        inputs = self.mappable(TX)
        checked: list[tuple[int, int, int]] = []
        for (index, sub), value in values.items():
            bits = inputs.get((index, sub))
            if bits is None:
                raise TargetError(f"0x{index:04X}:{sub:02X} is no input of {drive.device.type_name or 'the slave'} "
                                  f"(its inputs: {_names(inputs)})")
            value = int(value)
            entry = drive.objects.entries.get((index, sub))
            if entry is not None and entry.datatype is not None and entry.datatype.kind is Kind.SIGNED:
                low, high = -(1 << (bits - 1)), (1 << (bits - 1)) - 1
            else:
                low, high = 0, (1 << bits) - 1
            if not low <= value <= high:
                raise TargetError(f"0x{index:04X}:{sub:02X} is {bits} bit(s): {value} is not in {low}..{high}")
            checked.append((index, sub, value))
        for index, sub, value in checked:
            drive._put(index, sub, value)
        drive._log("inputs", **{f"{i:04X}:{s:02X}": v for i, s, v in checked})

    def outputs(self) -> dict[tuple[int, int], int]:
        """The outputs the slave holds, as the master last wrote them (:func:`mapped_values`)."""
        return mapped_values(self.drive, RX)

    def inputs(self) -> dict[tuple[int, int], int]:
        """The inputs the next image carries (:func:`mapped_values`)."""
        return mapped_values(self.drive, TX)


def mapped_values(drive: DriveApp, d: Direction) -> dict[tuple[int, int], int]:
    """The objects of ``drive``'s current process image in direction ``d`` (RX: the outputs, as the master last
    wrote them; TX: the inputs), by (index, sub), each its mapped bits as an unsigned integer."""
    stored = drive.objects.store.get
    values: dict[tuple[int, int], int] = {}
    for index, sub, _offset, bits in drive.layout[d].entries:
        if index:
            values[(index, sub)] = int.from_bytes(stored((index, sub), b""), "little") & ((1 << bits) - 1)
    return values


def _names(keys: Mapping[tuple[int, int], int]) -> str:
    shown = [f"0x{i:04X}:{s:02X}" for i, s in sorted(keys)[:4]]
    return ", ".join(shown) + (" …" if len(keys) > 4 else "") if shown else "none"
