"""The simulator target: a master with simulated drives (the default target of every "apply" command)."""

from __future__ import annotations

from collections.abc import Iterable

from ecattool.errors import SelectionError
from ecattool.esi.model import Device
from ecattool.target.base import SlaveTarget


class SimTarget:
    """A :class:`~ecattool.target.base.Target` whose slaves are :class:`ecattool.sim.Drive` objects."""

    def __init__(self, drives: Iterable[SlaveTarget]) -> None:
        self._drives = list(drives)
        for i, d in enumerate(self._drives):
            d.position = i

    @classmethod
    def from_devices(cls, devices: Iterable[Device]) -> "SimTarget":
        """One simulated drive per device (built-in profile devices or ESI devices), in bus order.

        ESI devices get their default modules plugged in and the communication objects their ESI leaves
        out (``profiles.complete_generic``), as :meth:`Drive.from_esi` does."""
        from ecattool.sim.slave import drive_for_device

        return cls([drive_for_device(d) for d in devices])

    def slaves(self) -> list[SlaveTarget]:
        return list(self._drives)

    def slave(self, position: int) -> SlaveTarget:
        try:
            return self._drives[position]
        except IndexError:
            raise SelectionError(f"no slave at position {position} (the bus has {len(self._drives)})") from None

    def close(self) -> None:
        self._drives = []

