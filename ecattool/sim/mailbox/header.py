"""The 6-byte EtherCAT mailbox header and the mailbox error reply (ETG.1000.4 §5.6, ETG.1000.6 §5.2).

    octets 0-1  Length   (UINT16, bytes of mailbox data after the header)
    octets 2-3  Address  (UINT16, station address of the originator; 0 = the master)
    octet  4    Channel (bits 0-5), Priority (bits 6-7)
    octet  5    Type (bits 0-3: 0 error, 1 AoE, 2 EoE, 3 CoE, 4 FoE, 5 SoE, 15 VoE), Counter (bits 4-6), reserved
"""

from __future__ import annotations

import struct
from dataclasses import dataclass
from enum import IntEnum

HEADER_SIZE = 6


class MailboxType(IntEnum):
    ERROR = 0x0
    AOE = 0x1
    EOE = 0x2
    COE = 0x3
    FOE = 0x4
    SOE = 0x5
    VOE = 0xF


#: protocol name in an ESI ``<Mailbox>`` element / the SII general category -> mailbox type
PROTOCOL_TYPES: dict[str, MailboxType] = {"AoE": MailboxType.AOE, "EoE": MailboxType.EOE, "CoE": MailboxType.COE,
                                          "FoE": MailboxType.FOE, "SoE": MailboxType.SOE, "VoE": MailboxType.VOE}


class MailboxError(IntEnum):
    """Detail codes of the mailbox error reply (ETG.1000.4 Table 30)."""

    SYNTAX = 0x0001
    UNSUPPORTED_PROTOCOL = 0x0002
    INVALID_CHANNEL = 0x0003
    SERVICE_NOT_SUPPORTED = 0x0004
    INVALID_HEADER = 0x0005
    SIZE_TOO_SHORT = 0x0006
    NO_MORE_MEMORY = 0x0007
    INVALID_SIZE = 0x0008


@dataclass(frozen=True, slots=True)
class MailboxHeader:
    length: int
    address: int = 0
    channel: int = 0
    priority: int = 0
    type: int = MailboxType.COE
    counter: int = 0

    @classmethod
    def parse(cls, frame: bytes) -> "MailboxHeader":
        """The header at the start of ``frame`` (at least 6 bytes)."""
        length, address, chan_prio, type_cnt = struct.unpack_from("<HHBB", frame, 0)
        return cls(length, address, chan_prio & 0x3F, chan_prio >> 6, type_cnt & 0x0F, (type_cnt >> 4) & 0x07)

    def pack(self) -> bytes:
        return struct.pack("<HHBB", self.length, self.address, (self.channel & 0x3F) | ((self.priority & 3) << 6),
                           (self.type & 0x0F) | ((self.counter & 7) << 4))


def next_counter(counter: int) -> int:
    """The mailbox counter sequence: 0 is the start value, after 7 comes 1 (ETG.1000.4)."""
    return 1 if counter >= 7 else counter + 1


def frame(mtype: int, data: bytes, counter: int) -> bytes:
    """A complete mailbox frame: header (length = len(data), address 0, channel 0, priority 0) + data."""
    return MailboxHeader(len(data), 0, 0, 0, mtype, counter).pack() + data


def error_data(code: MailboxError) -> bytes:
    """The data of a mailbox error reply (type 0): Type 0x0001 (MBXERR), Detail."""
    return struct.pack("<HH", 0x0001, int(code))


class MailboxRefused(Exception):
    """Raised by a protocol handler: answer the request with a mailbox error reply of ``code``."""

    def __init__(self, code: MailboxError) -> None:
        super().__init__(code.name)
        self.code = code
