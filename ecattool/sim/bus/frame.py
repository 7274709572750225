"""EtherCAT frames on Ethernet (EtherType 0x88A4): the frame header and its datagrams (ETG.1000.4 §5.3-5.4).

An Ethernet frame carries a 2-byte EtherCAT header (length in bits 0..10, type in bits 12..15; type 1 =
datagrams) and one or more datagrams. A datagram: command (1 byte), index (1), address (4: ADP + ADO for
position/node/broadcast addressing, one 32-bit logical address for LRD/LWR/LRW), length word (bits 0..10
data length, bit 14 circulated, bit 15 more datagrams follow), IRQ (2), data, working counter (2).
"""

from __future__ import annotations

import struct
from dataclasses import dataclass
from enum import IntEnum

ETHERTYPE_ECAT = 0x88A4
#: EtherCAT header type 1: the frame holds datagrams (DLPDU)
TYPE_DATAGRAMS = 1
ETH_HEADER = 14
#: the smallest Ethernet payload; shorter frames are padded to it
MIN_PAYLOAD = 46
_DG_HEAD = struct.Struct("<BBIHH")


class Cmd(IntEnum):
    NOP = 0
    APRD = 1
    APWR = 2
    APRW = 3
    FPRD = 4
    FPWR = 5
    FPRW = 6
    BRD = 7
    BWR = 8
    BRW = 9
    LRD = 10
    LWR = 11
    LRW = 12
    ARMW = 13
    FRMW = 14


class FrameError(ValueError):
    """An EtherCAT frame whose header or datagram lengths do not fit the bytes received."""


@dataclass(slots=True)
class Datagram:
    cmd: int
    index: int
    #: the 32-bit address field: ADP in the low 16 bits and ADO in the high 16 bits, or the logical address
    address: int
    data: bytearray
    irq: int = 0
    wkc: int = 0
    circulated: bool = False

    @property
    def adp(self) -> int:
        return self.address & 0xFFFF

    @property
    def ado(self) -> int:
        return (self.address >> 16) & 0xFFFF

    @classmethod
    def make(cls, cmd: int, adp: int, ado: int, data: bytes | int, index: int = 0) -> "Datagram":
        """A datagram addressed by ADP/ADO; ``data`` is the bytes to send or, for reads, their length."""
        payload = bytearray(data) if isinstance(data, (bytes, bytearray)) else bytearray(data)
        return cls(cmd, index, (adp & 0xFFFF) | ((ado & 0xFFFF) << 16), payload)

    @classmethod
    def logical(cls, cmd: int, address: int, data: bytes | int, index: int = 0) -> "Datagram":
        payload = bytearray(data) if isinstance(data, (bytes, bytearray)) else bytearray(data)
        return cls(cmd, index, address & 0xFFFFFFFF, payload)


def encode_datagrams(datagrams: list[Datagram]) -> bytes:
    """The EtherCAT header and the datagrams (no Ethernet header, no padding)."""
    body = bytearray()
    for i, d in enumerate(datagrams):
        if len(d.data) > 0x7FF:
            raise FrameError(f"datagram {i} carries {len(d.data)} bytes, at most 2047")
        length = len(d.data) | (0x4000 if d.circulated else 0) | (0x8000 if i < len(datagrams) - 1 else 0)
        body += _DG_HEAD.pack(d.cmd, d.index, d.address, length, d.irq) + d.data + struct.pack("<H", d.wkc)
    if len(body) > 0x7FF:
        raise FrameError(f"{len(body)} bytes of datagrams do not fit one frame")
    return struct.pack("<H", len(body) | (TYPE_DATAGRAMS << 12)) + bytes(body)


#: where one datagram lies in a frame: (offset of its header, command, index, address, length word, IRQ, working
#: counter); its data follow the 10-octet header, as many as the length word's bits 0..10 say
Head = tuple[int, int, int, int, int, int, int]
DG_HEAD_SIZE = _DG_HEAD.size


def datagram_heads(payload: bytes | bytearray, at: int = 0) -> list[Head]:
    """The datagrams of the EtherCAT payload (header first) that starts at offset ``at`` of ``payload``, where
    they lie. Raises FrameError on inconsistent lengths."""
    if len(payload) - at < 2:
        raise FrameError("no EtherCAT header")
    (head,) = struct.unpack_from("<H", payload, at)
    length, ftype = head & 0x7FF, head >> 12
    if ftype != TYPE_DATAGRAMS:
        raise FrameError(f"EtherCAT header type {ftype} is not 1 (datagrams)")
    if at + length + 2 > len(payload):
        raise FrameError(f"the header announces {length} bytes, the frame has {len(payload) - at - 2}")
    out: list[Head] = []
    pos, end = at + 2, at + 2 + length
    unpack = _DG_HEAD.unpack_from
    while True:
        if pos + _DG_HEAD.size + 2 > end:
            raise FrameError(f"datagram {len(out)} is cut short")
        cmd, index, address, dlen, irq = unpack(payload, pos)
        n = dlen & 0x7FF
        data_at = pos + _DG_HEAD.size
        if data_at + n + 2 > end:
            raise FrameError(f"datagram {len(out)} announces {n} data bytes past the end of the frame")
        out.append((pos, cmd, index, address, dlen, irq, payload[data_at + n] | payload[data_at + n + 1] << 8))
        pos = data_at + n + 2
        if not dlen & 0x8000:
            return out


def decode_datagrams(payload: bytes) -> list[Datagram]:
    """The datagrams of an EtherCAT payload (header first). Raises FrameError on inconsistent lengths."""
    out: list[Datagram] = []
    for pos, cmd, index, address, dlen, irq, wkc in datagram_heads(payload):
        data_at = pos + _DG_HEAD.size
        out.append(Datagram(cmd, index, address, bytearray(payload[data_at:data_at + (dlen & 0x7FF)]), irq, wkc,
                            bool(dlen & 0x4000)))
    return out


@dataclass(slots=True)
class Frame:
    """An Ethernet frame carrying EtherCAT datagrams."""

    dst: bytes
    src: bytes
    datagrams: list[Datagram]

    def to_bytes(self) -> bytes:
        payload = encode_datagrams(self.datagrams)
        raw = self.dst + self.src + struct.pack("!H", ETHERTYPE_ECAT) + payload
        return raw.ljust(ETH_HEADER + MIN_PAYLOAD, b"\x00")


BROADCAST = b"\xff" * 6


def carries_datagrams(raw: bytes | bytearray) -> bool:
    """Whether ``raw`` (an Ethernet frame) is an EtherCAT frame of datagrams: EtherType 0x88A4 (no VLAN tag) and
    an EtherCAT header of type 1."""
    return len(raw) >= ETH_HEADER + 2 and raw[12] == ETHERTYPE_ECAT >> 8 and raw[13] == ETHERTYPE_ECAT & 0xFF \
        and raw[ETH_HEADER + 1] >> 4 == TYPE_DATAGRAMS


def parse_frame(raw: bytes) -> Frame | None:
    """The EtherCAT frame in ``raw`` (an Ethernet frame without FCS), or None when it is not EtherCAT
    (another EtherType, a VLAN tag, a header of another type). Raises FrameError when it is EtherCAT but
    its lengths are inconsistent."""
    if not carries_datagrams(raw):
        return None
    return Frame(bytes(raw[0:6]), bytes(raw[6:12]), decode_datagrams(raw[ETH_HEADER:]))


def make_frame(datagrams: list[Datagram], src: bytes = b"\x01\x01\x01\x01\x01\x01") -> bytes:
    """A broadcast Ethernet frame with ``datagrams`` (what a master sends)."""
    return Frame(BROADCAST, src, datagrams).to_bytes()
