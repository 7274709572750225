"""The simulator's adapter: a master with simulated drives (the default target of every "apply" command), and
each drive as a live-bus slave with its SII (:class:`SimLiveSlave`, as ``sim serve`` gives it to a real master)."""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any

from ecattool.errors import SelectionError, TargetError
from ecattool.esi.model import Device, Identity
from ecattool.od.model import EcState, ObjectDictionary
from ecattool.sii.eeprom import read_sii, write_sequence
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



class SimLiveSlave:
    """A simulated drive (:class:`ecattool.sim.Drive`) with its SII, as the virtual bus serves them: a
    :class:`~ecattool.target.base.LiveSlave`. ``log`` collects the writes the drive was sent (SDO downloads,
    SII writes, refused writes too)."""

    def __init__(self, drive: Any, sii: bytes, log: list[str]) -> None:
        self.drive = drive
        self.position = int(drive.position)
        self.sii = bytes(sii)
        self._log = log
        self._seen = len(drive.events)

    def _note_writes(self) -> None:
        for e in self.drive.events[self._seen:]:
            # a write the drive refused was still sent: it counts
            if e.kind in ("sdo_download", "foe", "eeprom") or (e.kind == "sdo_abort" and e.data.get("op") != "upload"):
                self._log.append(f"slave {self.position}: {e.kind} {e.data}")
        self._seen = len(self.drive.events)

    def identity(self) -> Identity:
        from ecattool.sii.image import parse_header

        h = parse_header(self.sii)
        return Identity(h.vendor_id, h.product_code, h.revision, h.serial)

    def sdo_upload(self, index: int, subindex: int, complete_access: bool = False, size: int | None = None) -> bytes:
        try:
            return bytes(self.drive.sdo_upload(index, subindex, complete_access, size=size))
        finally:
            self._note_writes()

    def sdo_download(self, index: int, subindex: int, data: bytes, complete_access: bool = False,
                     expect_reply: bool = True) -> None:
        try:
            self.drive.sdo_download(index, subindex, data, complete_access, expect_reply)
        finally:
            self._note_writes()

    def state(self) -> EcState:
        state: EcState = self.drive.state()
        return state

    def request_state(self, state: EcState) -> None:
        self.drive.request_state(state)

    def exchange(self, outputs: bytes) -> bytes:
        return bytes(self.drive.exchange(outputs))

    def configure_dc(self, assign_activate: int, sync0_cycle_ns: int = 0, sync0_shift_ns: int = 0) -> None:
        self.drive.configure_dc(assign_activate, sync0_cycle_ns, sync0_shift_ns)

    def dc_activation(self) -> tuple[int, int, int]:
        """The drive's DC as a master configured it (the ESC's 0x0980-0x0981 word, SYNC0 and SYNC1 cycle in ns)."""
        act, cycle = getattr(self.drive, "dc", (0, 0))
        return int(act), int(cycle), 0

    def al_status_code(self) -> int | None:
        for e in reversed(self.drive.events):
            if e.kind in ("state", "state_refused"):
                return int(e.data.get("al_status", 0))
        return 0

    def sii_read(self) -> bytes:
        return read_sii(lambda word: self.sii[2 * word:2 * word + 8].ljust(8, b"\xff"))

    def sii_write(self, image: bytes) -> None:
        self._log.append(f"slave {self.position}: SII write of {len(image)} bytes")
        for word, data in write_sequence(image, self.sii):
            self.sii_write_word(word, data)

    def sii_write_word(self, word: int, data: bytes) -> None:
        if len(data) != 2 or word < 0:
            raise TargetError(f"slave {self.position}: SII word 0x{word:04X}: a write is one word (2 bytes)")
        sii = bytearray(self.sii.ljust(2 * word + 2, b"\xff"))
        sii[2 * word:2 * word + 2] = data
        self.sii = bytes(sii)

    def sdo_info(self) -> ObjectDictionary:
        dictionary: ObjectDictionary = self.drive.device.dictionary
        return dictionary


def live_slaves(drives: Iterable[Any], log: list[str]) -> list[SimLiveSlave]:
    """``drives`` as live-bus slaves in bus order, each with the SII ``ecattool sii build`` makes of its device (as
    ``sim serve`` gives it), taken to PRE-OP as a master's bus init does (the mailbox works from there)."""
    from ecattool.sii.builder import build

    slaves = []
    for i, d in enumerate(drives):
        d.position = i
        if d.state() is EcState.INIT:
            d.request_state(EcState.PREOP)
        slaves.append(SimLiveSlave(d, build(d.device).to_bytes(), log))
    return slaves
