"""FoE (File access over EtherCAT, ETG.1000.6 §5.8): write and read requests, data packets, ACK, BUSY and
ERR. The write request is checked by :meth:`Drive.foe_accepts` (Technosoft §17.4: FOESW_ setup files with
password 0 in PRE-OP/SAFE-OP/OP, FOEFW_ firmware in BOOT): a wrong name, password or state is refused at once
with an FoE error. The written file is handed whole to :meth:`Drive.foe_write`, which checks its content; a
refusal goes back as an FoE error with the drive's code and reason.

    OpCode (octet 0): 1 read request, 2 write request, 3 data, 4 ack, 5 error, 6 busy; octet 1 reserved
    octets 2-5: password (requests), packet number (data, ack), error code (error), Done/Entire (busy)
    then: file name (requests), data (data), error text (error)

A data packet shorter than the largest one that fits the mailbox ends the file; a file whose size is a
multiple of it ends with an empty packet.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from ecattool.errors import TargetError
from ecattool.sim.mailbox.header import HEADER_SIZE

if TYPE_CHECKING:
    from ecattool.sim.drive import Drive

READ, WRITE, DATA, ACK, ERROR, BUSY = 1, 2, 3, 4, 5, 6
FOE_OVERHEAD = 6

# FoE error codes (ETG.1000.6 Table 92)
NOT_DEFINED = 0x8000
NOT_FOUND = 0x8001
ILLEGAL = 0x8004
PACKET_NUMBER_WRONG = 0x8005
DISK_FULL = 0x8003

#: the largest file an FoE write may bring: the drive's memories are 64 K words (128 KiB) each, and a setup
#: image that writes every EEPROM word in a block of its own takes 6 octets per word; a firmware file is no
#: larger than the program memory. More is refused with "disk full" and dropped.
MAX_FILE_BYTES = 6 * 0x10000


@dataclass
class _Write:
    name: str
    password: int
    data: bytearray = field(default_factory=bytearray)
    next_packet: int = 1
    busy_left: int = 0


@dataclass
class _Read:
    data: bytes
    packet: int = 0
    offset: int = 0
    done: bool = False


class FoeServer:
    """``busy_replies``: how many BUSY answers the drive gives to the final data packet of a write (while it
    programs its EEPROM) before it takes the repeated packet; 0 = none. ``files``: what an FoE read may fetch,
    by name (the Technosoft drives offer nothing to read: empty by default, a read gets "not found")."""

    def __init__(self, drive: "Drive", out_size: int, in_size: int) -> None:
        self.drive = drive
        self.out_size = out_size
        self.in_size = in_size
        self.busy_replies = 0
        self.files: dict[str, bytes] = {}
        self._write: _Write | None = None
        self._read: _Read | None = None

    def reset(self) -> None:
        self._write = None
        self._read = None

    @staticmethod
    def error_data(code: int, text: str = "") -> bytes:
        return struct.pack("<BBI", ERROR, 0, code) + text.encode("ascii", "replace")

    def _error(self, code: int, text: str) -> list[bytes]:
        self.reset()
        room = max(0, self.in_size - HEADER_SIZE - FOE_OVERHEAD)
        return [self.error_data(code, text)[:FOE_OVERHEAD + room]]

    # ------------------------------------------------------------------------------------------
    def handle(self, data: bytes) -> list[bytes]:
        """``data``: the FoE mailbox data. Returns the FoE replies."""
        if len(data) < FOE_OVERHEAD:
            return self._error(ILLEGAL, "FoE request shorter than 6 octets")
        opcode = data[0]
        (word,) = struct.unpack_from("<I", data, 2)
        body = data[FOE_OVERHEAD:]
        if opcode == WRITE:
            self.reset()
            name = _file_name(body)
            try:  # the drive refuses a wrong name, password or state at once, before any data
                self.drive.foe_accepts(name, word)
            except TargetError as exc:
                return self._error(getattr(exc, "code", NOT_DEFINED), str(exc))
            self._write = _Write(name, word, busy_left=self.busy_replies)
            return [struct.pack("<BBI", ACK, 0, 0)]
        if opcode == DATA:
            return self._data(word, body)
        if opcode == READ:
            return self._start_read(_file_name(body), word)
        if opcode == ACK:
            return self._ack(word)
        if opcode == ERROR:  # the master gives up: no reply
            self.reset()
            return []
        return self._error(ILLEGAL, f"unknown FoE opcode {opcode}")

    # ------------------------------------------------------------------------------------------
    def _data(self, packet: int, chunk: bytes) -> list[bytes]:
        w = self._write
        if w is None:
            return self._error(ILLEGAL, "data packet without a write request")
        if packet == w.next_packet - 1 and packet > 0:  # our ACK was lost: the master repeats the packet
            return [struct.pack("<BBI", ACK, 0, packet)]
        if packet != w.next_packet:
            return self._error(PACKET_NUMBER_WRONG, f"packet {packet}, expected {w.next_packet}")
        full = max(1, self.out_size - HEADER_SIZE - FOE_OVERHEAD)
        if len(w.data) + min(len(chunk), full) > MAX_FILE_BYTES:
            return self._error(DISK_FULL, f"the file is larger than the {MAX_FILE_BYTES} octets the drive takes")
        if len(chunk) >= full:
            w.data += chunk[:full]
            w.next_packet += 1
            return [struct.pack("<BBI", ACK, 0, packet)]
        if w.busy_left > 0:  # still programming: the master sends this packet again
            w.busy_left -= 1
            return [struct.pack("<BBHH", BUSY, 0, 0, 100)]
        w.data += chunk
        self._write = None
        try:
            self.drive.foe_write(w.name, bytes(w.data), w.password)
        except TargetError as exc:  # the drive's FoeError carries the FoE error code
            return self._error(getattr(exc, "code", NOT_DEFINED), str(exc))
        return [struct.pack("<BBI", ACK, 0, packet)]

    def _room(self) -> int:
        return max(1, self.in_size - HEADER_SIZE - FOE_OVERHEAD)

    def _start_read(self, name: str, password: int) -> list[bytes]:
        self.reset()
        if name not in self.files:
            return self._error(NOT_FOUND, f"no file {name!r} to read")
        self._read = _Read(self.files[name])
        return self._next_data()

    def _next_data(self) -> list[bytes]:
        r = self._read
        assert r is not None
        chunk = r.data[r.offset:r.offset + self._room()]
        r.offset += len(chunk)
        r.packet += 1
        r.done = len(chunk) < self._room()
        return [struct.pack("<BBI", DATA, 0, r.packet) + chunk]

    def _ack(self, packet: int) -> list[bytes]:
        r = self._read
        if r is None or packet != r.packet:
            return self._error(PACKET_NUMBER_WRONG if r is not None else ILLEGAL,
                               f"unexpected ACK of packet {packet}")
        if r.done:
            self._read = None
            return []
        return self._next_data()


def _file_name(body: bytes) -> str:
    return body.split(b"\x00", 1)[0].decode("latin-1")
