"""CoE over the mailbox: the SDO server (expedited, normal and segmented upload/download, complete access,
abort) and Emergency messages (ETG.1000.6 §5.6). The drive decides every request through its public SDO API
(:meth:`Drive.sdo_upload` / :meth:`Drive.sdo_download`); this module only frames and sequences.

CoE header (2 octets after the mailbox header): Number (bits 0-8), Service (bits 12-15): 1 Emergency,
2 SDO request, 3 SDO response, 8 SDO information. The SDO command octet: bits 5-7 the command specifier,
bit 4 complete access (initiate) or toggle (segment), bits 2-3 / 1-3 unused octets, bit 1 expedited, bit 0 size
indicated (initiate) or last segment (segment).
"""

from __future__ import annotations

import struct
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, TypeVar

from ecattool.errors import EcatToolError, SdoAbort, SdoTimeout
from ecattool import abort as A
from ecattool.sim.mailbox.header import HEADER_SIZE, MailboxError, MailboxRefused

if TYPE_CHECKING:
    from ecattool.sim.drive import Drive, Emergency

_T = TypeVar("_T")

SERVICE_EMERGENCY = 1
SERVICE_SDO_REQUEST = 2
SERVICE_SDO_RESPONSE = 3
SERVICE_SDO_INFO = 8

# client command specifiers (bits 5-7 of the command octet of a request)
CCS_DOWNLOAD_SEGMENT = 0
CCS_DOWNLOAD = 1
CCS_UPLOAD = 2
CCS_UPLOAD_SEGMENT = 3
CCS_ABORT = 4
# server command specifiers (responses)
SCS_UPLOAD_SEGMENT = 0
SCS_DOWNLOAD_SEGMENT = 1
SCS_UPLOAD = 2
SCS_DOWNLOAD = 3

TOGGLE_NOT_ALTERNATED = 0x05030000

#: the most a segmented download may announce for an object of variable length (a string, a domain) or a
#: complete access: the simulated drive keeps what it is sent in memory, so a master cannot make it hold more
MAX_SDO_BYTES = 1 << 20

#: octets of a full SDO frame: CoE header, command, index, sub-index, 4 data octets (the minimum size)
SDO_FRAME = 10
#: octets before the data of a normal initiate frame (mailbox header + SDO_FRAME with the size in its data)
NORMAL_OVERHEAD = HEADER_SIZE + SDO_FRAME
#: octets before the data of a segment frame (mailbox header + CoE header + command)
SEGMENT_OVERHEAD = HEADER_SIZE + 3


def coe_header(service: int, number: int = 0) -> bytes:
    return struct.pack("<H", (number & 0x1FF) | (service << 12))


def sdo_abort_data(index: int, subindex: int, code: int) -> bytes:
    """An Abort SDO Transfer request (sent with the SDO request service, as ETG.1000.6 defines it)."""
    return coe_header(SERVICE_SDO_REQUEST) + struct.pack("<BHBI", CCS_ABORT << 5, index, subindex, code)


def emergency_data(emcy: "Emergency") -> bytes:
    """The CoE Emergency message: error code, error register, 5 manufacturer octets."""
    return coe_header(SERVICE_EMERGENCY) + emcy.to_bytes()


@dataclass
class _Transfer:
    """A segmented transfer in progress."""

    upload: bool
    index: int
    subindex: int
    complete_access: bool
    size: int
    data: bytearray = field(default_factory=bytearray)
    toggle: int = 0


class SdoServer:
    """Serves SDO requests for one drive. ``handle`` takes the mailbox data of one CoE SDO request (from the
    CoE header on) and returns the CoE replies to send (none when the drive sends no reply)."""

    def __init__(self, drive: "Drive", out_size: int, in_size: int) -> None:
        self.drive = drive
        self.out_size = out_size
        self.in_size = in_size
        self._transfer: _Transfer | None = None

    def reset(self) -> None:
        self._transfer = None

    # ------------------------------------------------------------------------------------------
    def handle(self, data: bytes) -> list[bytes]:
        if len(data) < SDO_FRAME:
            raise MailboxRefused(MailboxError.SIZE_TOO_SHORT)
        command = data[2]
        ccs = command >> 5
        if ccs == CCS_ABORT:  # the master gives up a transfer: no reply
            self._transfer = None
            return []
        if ccs == CCS_UPLOAD_SEGMENT:
            return self._upload_segment(command)
        if ccs == CCS_DOWNLOAD_SEGMENT:
            return self._download_segment(data)
        index, subindex = struct.unpack_from("<HB", data, 3)
        self._transfer = None  # a new initiate ends any transfer in progress (CiA-301)
        if ccs == CCS_UPLOAD:
            return self._upload(index, subindex, bool(command & 0x10))
        if ccs == CCS_DOWNLOAD:
            return self._download(data, command, index, subindex)
        return [sdo_abort_data(index, subindex, A.COMMAND_INVALID)]  # block transfers (5, 6) and 7

    # ------------------------------------------------------------------------------------------
    @staticmethod
    def _ask(index: int, subindex: int, call: Callable[[], _T]) -> _T | list[bytes]:
        """The drive's answer to one request, or its refusal as the frames to send instead: an abort with its
        code, or nothing at all where the drive sends no reply."""
        try:
            return call()
        except SdoTimeout:
            return []
        except SdoAbort as exc:
            return [sdo_abort_data(index, subindex, exc.code)]
        except EcatToolError:
            return [sdo_abort_data(index, subindex, A.GENERAL_ERROR)]

    def _call_download(self, index: int, subindex: int, value: bytes, ca: bool) -> list[bytes] | None:
        """None when the drive accepted the download, else the replies to send instead of the confirmation."""
        refused = self._ask(index, subindex,
                            lambda: self.drive.sdo_download(index, subindex, value, complete_access=ca))
        return refused if isinstance(refused, list) else None

    def _upload(self, index: int, subindex: int, ca: bool) -> list[bytes]:
        value = self._ask(index, subindex, lambda: self.drive.sdo_upload(index, subindex, complete_access=ca))
        if isinstance(value, list):
            return value
        ca_bit = 0x10 if ca else 0
        head = coe_header(SERVICE_SDO_RESPONSE)
        if 0 < len(value) <= 4 and not ca:  # an empty value (a blank string) goes normal, with size 0
            command = (SCS_UPLOAD << 5) | ((4 - len(value)) << 2) | 0x03  # expedited, size indicated
            return [head + struct.pack("<BHB", command, index, subindex) + value.ljust(4, b"\x00")]
        room = max(0, self.in_size - NORMAL_OVERHEAD)
        first = value[:room]
        reply = head + struct.pack("<BHBI", (SCS_UPLOAD << 5) | ca_bit | 0x01, index, subindex, len(value)) + first
        if len(first) < len(value):
            self._transfer = _Transfer(True, index, subindex, ca, len(value), bytearray(value[len(first):]))
        return [reply]

    def _upload_segment(self, command: int) -> list[bytes]:
        t = self._transfer
        if t is None or not t.upload:
            return [sdo_abort_data(0, 0, A.COMMAND_INVALID)]
        toggle = command & 0x10
        if toggle != t.toggle:
            self._transfer = None
            return [sdo_abort_data(t.index, t.subindex, TOGGLE_NOT_ALTERNATED)]
        room = max(1, self.in_size - SEGMENT_OVERHEAD)
        chunk = bytes(t.data[:room])
        del t.data[:room]
        last = not t.data
        command = (SCS_UPLOAD_SEGMENT << 5) | toggle | (0x01 if last else 0)
        if len(chunk) < 7:
            command |= (7 - len(chunk)) << 1
            chunk = chunk.ljust(7, b"\x00")
        t.toggle ^= 0x10
        if last:
            self._transfer = None
        return [coe_header(SERVICE_SDO_RESPONSE) + bytes([command]) + chunk]

    def _download(self, data: bytes, command: int, index: int, subindex: int) -> list[bytes]:
        ca = bool(command & 0x10)
        if command & 0x02:  # expedited
            size = 4 - ((command >> 2) & 0x03) if command & 0x01 else 4
            value = data[6:6 + size]
            complete = True
        else:
            if len(data) < SDO_FRAME:
                raise MailboxRefused(MailboxError.SIZE_TOO_SHORT)
            size = struct.unpack_from("<I", data, 6)[0]
            value = data[10:10 + size]
            complete = len(value) >= size
        if complete:
            refused = self._call_download(index, subindex, bytes(value), ca)
            if refused is not None:
                return refused
        else:
            # what no data can make writable is refused at the initiate, as a slave stack does: a read-only or
            # missing object never gets to buffer its segments
            refused = self._ask(index, subindex,
                                lambda: self.drive.check_download(index, subindex, complete_access=ca))
            if isinstance(refused, list):
                return refused
            too_long = self._announced_too_long(index, subindex, ca, size)
            if too_long:
                return [sdo_abort_data(index, subindex, too_long)]
            self._transfer = _Transfer(False, index, subindex, ca, size, bytearray(value))
        command = (SCS_DOWNLOAD << 5) | (0x10 if ca else 0)
        return [coe_header(SERVICE_SDO_RESPONSE) + struct.pack("<BHBI", command, index, subindex, 0)]

    def _announced_too_long(self, index: int, subindex: int, ca: bool, size: int) -> int:
        """The abort code for a segmented download whose announced size no transfer to this object may have,
        checked at the initiate as a slave stack does (0 when it may go on): more octets than an object of fixed
        size has (0x06070012), or more than :data:`MAX_SDO_BYTES` (0x05040005, out of memory)."""
        entry = None if ca else self.drive.device.dictionary.entry(index, subindex)
        bits = entry.datatype.bits if entry is not None and entry.datatype is not None else None
        if bits is not None and size > (max(bits, entry.bit_size if entry is not None else 0) + 7) // 8:
            return A.LENGTH_TOO_HIGH
        return A.OUT_OF_MEMORY if size > MAX_SDO_BYTES else 0

    def _download_segment(self, data: bytes) -> list[bytes]:
        t = self._transfer
        command = data[2]
        if t is None or t.upload:
            return [sdo_abort_data(0, 0, A.COMMAND_INVALID)]
        toggle = command & 0x10
        if toggle != t.toggle:
            self._transfer = None
            return [sdo_abort_data(t.index, t.subindex, TOGGLE_NOT_ALTERNATED)]
        chunk = data[3:]
        if len(data) == SDO_FRAME:  # a minimum-size segment says how many of its 7 octets are unused
            chunk = chunk[:7 - ((command >> 1) & 0x07)]
        t.data += chunk
        t.toggle ^= 0x10
        reply = [coe_header(SERVICE_SDO_RESPONSE) + bytes([(SCS_DOWNLOAD_SEGMENT << 5) | toggle]) + bytes(7)]
        if not command & 0x01:
            if len(t.data) > t.size:
                self._transfer = None
                return [sdo_abort_data(t.index, t.subindex, A.LENGTH_TOO_HIGH)]
            return reply
        self._transfer = None
        if len(t.data) != t.size:
            return [sdo_abort_data(t.index, t.subindex, A.LENGTH_MISMATCH)]
        refused = self._call_download(t.index, t.subindex, bytes(t.data), t.complete_access)
        return reply if refused is None else refused
