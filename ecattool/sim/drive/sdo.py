"""The SDO server side of the object dictionary: uploads and downloads with the drive's access, state, length
and range rules and abort codes, complete access, and the SDO faults a test plans (:class:`~ecattool.sim.Faults`)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from ecattool import abort as A
from ecattool.errors import SdoAbort, SdoTimeout, SdoTooLarge
from ecattool.od.model import MAILBOX_STATES, Entry, ObjectCode
from ecattool.od.types import Kind
from ecattool.sim import eeprom as ee
from ecattool.sim.drive.core import Store, decode_int, sdo_abort
from ecattool.sim.drive.pdo import PdoConfig, is_assign, is_mapping

if TYPE_CHECKING:
    from ecattool.sim.drive.app import DriveApp


class SdoServer:
    """The SDO access part: upload/download with the dictionary's access, state, length and range rules (mapping
    and assignment writes go through the :class:`PdoConfig` part it is given), and the objects' handlers."""

    def __init__(self, drive: DriveApp, pdo: PdoConfig) -> None:
        self.drive = drive
        self.pdo = pdo

    def sdo_upload(self, index: int, subindex: int, complete_access: bool = False, size: int | None = None) -> bytes:
        """The value of ``index:subindex``; ``size``: the most octets the master's buffer takes (a longer value is
        an SdoTooLarge, as a master with a buffer of that size refuses it; ``target.base.SlaveTarget``)."""
        drive = self.drive
        planned = drive.faults.next_sdo()
        if not drive.device.has_coe:  # a fixed process image (an EL2008): no mailbox answers
            drive._log("sdo_timeout", index=index, subindex=subindex, reason="the slave has no CoE mailbox")
            raise SdoTimeout(index, subindex)
        if drive.esm not in MAILBOX_STATES:
            drive._log("sdo_timeout", index=index, subindex=subindex, reason=f"no mailbox in {drive.esm.value}")
            raise SdoTimeout(index, subindex)
        if planned is not None:
            self._planned(planned, index, subindex)
        try:
            data = self._ca_upload(index, subindex) if complete_access else self._upload(index, subindex)
        except SdoAbort as exc:
            drive._log("sdo_abort", op="upload", index=index, subindex=subindex, code=exc.code)
            raise
        if planned is not None and planned[0] == "drop":
            drive._log("sdo_timeout", index=index, subindex=subindex, reason="reply dropped (fault injection)")
            raise SdoTimeout(index, subindex)
        drive._log("sdo_upload", index=index, subindex=subindex, data=data.hex())
        if size is not None and len(data) > size:
            raise SdoTooLarge(index, subindex, drive.position, size, len(data))
        return data

    def sdo_download(self, index: int, subindex: int, data: bytes, complete_access: bool = False,
                     expect_reply: bool = True) -> None:
        drive = self.drive
        planned = drive.faults.next_sdo()
        if not drive.device.has_coe:  # a fixed process image (an EL2008): no mailbox answers
            drive._log("sdo_timeout", index=index, subindex=subindex, reason="the slave has no CoE mailbox")
            raise SdoTimeout(index, subindex)
        if drive.esm not in MAILBOX_STATES:
            drive._log("sdo_timeout", index=index, subindex=subindex, reason=f"no mailbox in {drive.esm.value}")
            raise SdoTimeout(index, subindex)
        if planned is not None:
            if planned[0] == "drop" and not planned[1]:
                drive._log("sdo_timeout", index=index, subindex=subindex, reason="request lost (fault injection)")
                raise SdoTimeout(index, subindex)
            self._planned(planned, index, subindex)
        data = bytes(data)
        try:
            if complete_access:
                self._ca_download(index, subindex, data)
                no_reply = False
            else:
                no_reply = self._download(index, subindex, data)
        except SdoAbort as exc:
            drive._log("sdo_abort", op="download", index=index, subindex=subindex, data=data.hex(), code=exc.code)
            raise
        except ee.PowerLost:
            drive.nonvolatile.power_loss()
            raise SdoTimeout(index, subindex) from None
        drive._log("sdo_download", index=index, subindex=subindex, data=data.hex())
        if no_reply or (planned is not None and planned[0] == "drop"):
            if expect_reply:
                drive._log("sdo_timeout", index=index, subindex=subindex, reason="the drive sends no reply")
                raise SdoTimeout(index, subindex)

    def check_download(self, index: int, subindex: int, complete_access: bool = False) -> None:
        """Raise the abort a download to ``index:subindex`` gets whatever its data: an object or entry that does not
        exist, one read only via the mailbox (PDO only), read-only, or not writable in the current state. A slave
        stack checks this at the initiate of a segmented download, before it takes any segment."""
        drive = self.drive
        try:
            if complete_access:
                self._ca_supported(index, subindex)
                return
            e = self._entry(index, subindex)
            self._pdo_only(index, subindex)
            if not e.access.write or (subindex and index in drive._read_only_set):
                raise sdo_abort(index, subindex, A.READ_ONLY)
            if drive.esm not in e.access.write:
                raise sdo_abort(index, subindex, A.DATA_CANNOT_BE_STORED_STATE)
        except SdoAbort as exc:
            drive._log("sdo_abort", op="download", index=index, subindex=subindex, data="", code=exc.code)
            raise

    def _planned(self, planned: tuple[str, int], index: int, subindex: int) -> None:
        drive = self.drive
        if planned[0] == "abort":
            drive._log("sdo_abort", op="injected", index=index, subindex=subindex, code=planned[1])
            raise sdo_abort(index, subindex, planned[1])

    def _entry(self, index: int, sub: int) -> Entry:
        drive = self.drive
        e = drive.objects.entries.get((index, sub))
        if e is None:
            if index not in drive.device.dictionary:
                raise sdo_abort(index, sub, A.OBJECT_DOES_NOT_EXIST)
            raise sdo_abort(index, sub, A.SUBINDEX_DOES_NOT_EXIST)
        return e

    def _pdo_only(self, index: int, sub: int) -> None:
        drive = self.drive
        if index in drive._pdo_only_set:
            raise sdo_abort(index, sub, A.UNSUPPORTED_ACCESS)  # Control Techniques 8.5: 2830h/2831h cyclic only

    def _upload(self, index: int, sub: int) -> bytes:
        drive = self.drive
        e = self._entry(index, sub)
        self._pdo_only(index, sub)
        if not e.access.read:
            raise sdo_abort(index, sub, A.WRITE_ONLY)
        if drive.esm not in e.access.read:
            raise sdo_abort(index, sub, A.DATA_CANNOT_BE_STORED_STATE)
        handler = drive._handlers_up.get(index)
        if handler is not None:
            return handler(sub)
        return drive.objects.store[(index, sub)]

    def _ca_supported(self, index: int, sub: int) -> None:
        drive = self.drive
        mb = drive.device.mailbox
        if mb is None or mb.coe is None or not mb.coe.complete_access:
            raise sdo_abort(index, sub, A.COMPLETE_ACCESS_NOT_SUPPORTED)
        obj = drive.device.dictionary.get(index)
        if obj is None:
            raise sdo_abort(index, sub, A.OBJECT_DOES_NOT_EXIST)
        if obj.object_code is ObjectCode.VAR or sub > 1:
            raise sdo_abort(index, sub, A.UNSUPPORTED_ACCESS)

    def _ca_subs(self, index: int, first: int) -> list[int]:
        drive = self.drive
        return sorted(s for (i, s) in drive.objects.entries if i == index and s >= first)

    def _ca_upload(self, index: int, sub: int) -> bytes:
        """Complete access: sub-index 0 padded to 16 bits, then every entry bit-packed (ETG.1000.6)."""
        drive = self.drive
        self._ca_supported(index, sub)
        acc = 0
        nbits = 0
        for s in self._ca_subs(index, sub):
            raw = self._upload(index, s)
            e = drive.objects.entries[(index, s)]
            bits = 16 if s == 0 else (e.bit_size or 8 * len(raw))
            acc |= (int.from_bytes(raw, "little") & ((1 << bits) - 1)) << nbits
            nbits += bits
        return acc.to_bytes((nbits + 7) // 8, "little")

    def _download(self, index: int, sub: int, data: bytes) -> bool:
        """Check and apply one download; returns True when the drive sends no reply (2080h reset)."""
        drive = self.drive
        e = self._entry(index, sub)
        self._pdo_only(index, sub)
        if not e.access.write or (sub and index in drive._read_only_set):
            raise sdo_abort(index, sub, A.READ_ONLY)
        if drive.esm not in e.access.write:
            raise sdo_abort(index, sub, A.DATA_CANNOT_BE_STORED_STATE)
        size = e.byte_size
        dt = e.datatype
        variable = dt is not None and dt.bits is None
        if variable:
            if size and len(data) > size:
                raise sdo_abort(index, sub, A.LENGTH_TOO_HIGH)
        elif len(data) != size:
            raise sdo_abort(index, sub, A.LENGTH_TOO_HIGH if len(data) > size else A.LENGTH_TOO_LOW)
        value: int | None = None
        if dt is not None and dt.kind in (Kind.SIGNED, Kind.UNSIGNED, Kind.BITS, Kind.BOOL):
            value = decode_int(e, data)
            if e.minimum is not None and value < e.minimum:
                raise sdo_abort(index, sub, A.VALUE_TOO_LOW)
            if e.maximum is not None and value > e.maximum:
                raise sdo_abort(index, sub, A.VALUE_TOO_HIGH)
            if e.values is not None and value not in e.values and (index, sub) != (0x6060, 0):
                # a value list's gap (decision Profiles-2); modes of operation are the mode handler's (0 = none)
                raise sdo_abort(index, sub, A.INVALID_VALUE)
        elif dt is not None and dt.kind is Kind.REAL:
            f = dt.decode(data)
            if e.minimum is not None and f < e.minimum:
                raise sdo_abort(index, sub, A.VALUE_TOO_LOW)
            if e.maximum is not None and f > e.maximum:
                raise sdo_abort(index, sub, A.VALUE_TOO_HIGH)
        if variable and size:
            data = data.ljust(size, b"\x00")
        d = is_mapping(index)
        if d is not None:
            self.pdo._mapping_write(d, index, sub, value if value is not None else 0)
        else:
            d = is_assign(index)
            if d is not None:
                self.pdo._assign_write(d, index, sub, value if value is not None else 0)
        handler = drive._handlers_down.get(index)
        if handler is not None:
            result = handler(sub, data, value)
            if result is None:
                return True  # no reply (reset)
            if not result:
                return False
        drive.objects.store[(index, sub)] = data
        if index in drive._after_write:
            drive._after_write[index](sub, value)
        return False

    def _ca_unchanged(self, index: int, sub: int, chunk: bytes) -> None:
        """A read-only entry inside a complete access download: passed over when the data carries the value it
        holds, refused (0601 0002h) when the write would change it — a Fixed PDO's mapping written by complete
        access is not silently left as it was (as a single write of it is refused)."""
        drive = self.drive
        held = drive.objects.store.get((index, sub), b"")
        if int.from_bytes(chunk, "little") != int.from_bytes(held[:len(chunk)], "little"):
            raise sdo_abort(index, sub, A.READ_ONLY)

    def _ca_download(self, index: int, sub: int, data: bytes) -> None:
        """Complete access download: applied as the single writes a master would make, all or nothing."""
        drive = self.drive
        self._ca_supported(index, sub)
        subs = self._ca_subs(index, sub)
        pos = 0
        writes: list[tuple[int, bytes]] = []
        for s in subs:
            e = drive.objects.entries[(index, s)]
            nbytes = 2 if s == 0 else max(1, e.byte_size)
            if pos + nbytes > len(data):
                break
            chunk = data[pos:pos + nbytes]
            writes.append((s, chunk[:1] if s == 0 else chunk))
            pos += nbytes
        if pos != len(data) or not writes:
            raise sdo_abort(index, sub, A.LENGTH_MISMATCH if writes else A.LENGTH_TOO_LOW)
        snapshot = Store(drive.objects.store)
        try:
            if writes[0][0] == 0:
                count = writes[0][1]
                e0 = drive.objects.entries[(index, 0)]
                if e0.access.write:
                    self._download(index, 0, b"\x00")
                for s, chunk in writes[1:]:
                    if drive.objects.entries[(index, s)].access.write:
                        self._download(index, s, chunk)
                    else:
                        self._ca_unchanged(index, s, chunk)
                if e0.access.write:
                    self._download(index, 0, count)
                else:
                    self._ca_unchanged(index, 0, count)
            else:
                for s, chunk in writes:
                    self._download(index, s, chunk)
        except SdoAbort:
            drive.objects.store = snapshot
            raise
