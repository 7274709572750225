"""SDO Information service (CoE service 8, ETG.1000.6 §5.6.3): OD list, object description and entry
description, answered from the drive's dictionary (``drive.device.dictionary``).

SDO information header (after the CoE header): OpCode (bits 0-6), Incomplete (bit 7), a reserved octet and
Fragments Left (UINT16). A response longer than the mailbox goes out in fragments: each carries the number of
fragments still to come and all but the last have the Incomplete bit set.
"""

from __future__ import annotations

import struct
from typing import TYPE_CHECKING

from ecattool.errors import EcatToolError
from ecattool import abort as A
from ecattool.od.model import EcState, Entry, ObjectCode, OdObject
from ecattool.od.types import Kind
from ecattool.sim.mailbox.coe import SERVICE_SDO_INFO, coe_header
from ecattool.sim.mailbox.header import HEADER_SIZE, MailboxError, MailboxRefused

if TYPE_CHECKING:
    from ecattool.sim.drive import Drive

OD_LIST_REQ, OD_LIST_RES = 1, 2
OBJECT_DESC_REQ, OBJECT_DESC_RES = 3, 4
ENTRY_DESC_REQ, ENTRY_DESC_RES = 5, 6
INFO_ERROR = 7

#: OD list types
LIST_LENGTHS, LIST_ALL, LIST_RX_MAPPABLE, LIST_TX_MAPPABLE, LIST_BACKUP, LIST_SETTINGS = range(6)

#: object codes on the wire (CiA-301)
OBJECT_CODES = {ObjectCode.VAR: 7, ObjectCode.ARRAY: 8, ObjectCode.RECORD: 9}

#: value info bits of an entry description (the access, object category and PDO mapping are always sent)
VALUE_INFO_ALWAYS = 0x07
VALUE_INFO_DEFAULT = 0x10
VALUE_INFO_MINIMUM = 0x20
VALUE_INFO_MAXIMUM = 0x40

#: the standard complex data types of the communication area (CiA-301 DEFSTRUCT indices)
_RECORD_TYPES = [(0x1018, 0x1018, 0x0023), (0x1400, 0x15FF, 0x0020), (0x1600, 0x17FF, 0x0021),
                 (0x1800, 0x19FF, 0x0020), (0x1A00, 0x1BFF, 0x0021)]

#: octets of the mailbox data before a fragment's payload: CoE header and SDO information header
INFO_OVERHEAD = 2 + 4


def object_access(e: Entry) -> int:
    """The ObjectAccess word: read/write per state (bits 0-5), RxPDO/TxPDO mappable (6, 7), backup (8),
    settings (9)."""
    bits = 0
    for i, s in enumerate((EcState.PREOP, EcState.SAFEOP, EcState.OP)):
        if s in e.access.read:
            bits |= 1 << i
        if s in e.access.write:
            bits |= 1 << (3 + i)
    bits |= (0x40 if e.rx_mappable else 0) | (0x80 if e.tx_mappable else 0)
    bits |= (0x100 if e.backup else 0) | (0x200 if e.setting else 0)
    return bits


def _data_type(obj: OdObject) -> int:
    if obj.object_code is ObjectCode.RECORD:
        for low, high, code in _RECORD_TYPES:
            if low <= obj.index <= high:
                return code
        return 0
    e = obj.entries.get(1 if obj.object_code is ObjectCode.ARRAY else 0) or next(iter(obj), None)
    return e.datatype.code if e is not None and e.datatype is not None else 0


def _name(text: str) -> bytes:
    return text.encode("utf-8", "replace")


class SdoInfoServer:
    def __init__(self, drive: "Drive", in_size: int) -> None:
        self.drive = drive
        self.in_size = in_size

    @property
    def supported(self) -> bool:
        mb = self.drive.device.mailbox
        return mb is not None and mb.coe is not None and mb.coe.sdo_info

    def handle(self, data: bytes) -> list[bytes]:
        """``data``: the mailbox data from the CoE header on. Returns the CoE replies (fragments)."""
        if not self.supported:
            raise MailboxRefused(MailboxError.SERVICE_NOT_SUPPORTED)
        if len(data) < INFO_OVERHEAD + 2:
            raise MailboxRefused(MailboxError.SIZE_TOO_SHORT)
        opcode = data[2] & 0x7F
        body = data[INFO_OVERHEAD:]
        if opcode == OD_LIST_REQ:
            return self._od_list(struct.unpack_from("<H", body)[0])
        if opcode == OBJECT_DESC_REQ:
            return self._object_description(struct.unpack_from("<H", body)[0])
        if opcode == ENTRY_DESC_REQ:
            if len(body) < 4:
                raise MailboxRefused(MailboxError.SIZE_TOO_SHORT)
            index, sub, info = struct.unpack_from("<HBB", body)
            return self._entry_description(index, sub, info)
        return [self._error(A.COMMAND_INVALID)]

    # ------------------------------------------------------------------------------------------
    def _fragments(self, opcode: int, payload: bytes, unit: int = 1) -> list[bytes]:
        """Split ``payload`` into fragments that fit SM1 (cut at multiples of ``unit`` octets)."""
        room = max(unit, (self.in_size - HEADER_SIZE - INFO_OVERHEAD) // unit * unit)
        pieces = [payload[i:i + room] for i in range(0, len(payload), room)] or [b""]
        out = []
        for n, piece in enumerate(pieces):
            left = len(pieces) - 1 - n
            out.append(coe_header(SERVICE_SDO_INFO) + struct.pack("<BBH", opcode | (0x80 if left else 0), 0, left)
                       + piece)
        return out

    def _error(self, code: int) -> bytes:
        return coe_header(SERVICE_SDO_INFO) + struct.pack("<BBHI", INFO_ERROR, 0, 0, code)

    def _od_list(self, list_type: int) -> list[bytes]:
        objects = list(self.drive.device.dictionary)
        lists = [
            [o.index for o in objects],
            [o.index for o in objects if any(e.rx_mappable for e in o)],
            [o.index for o in objects if any(e.tx_mappable for e in o)],
            [o.index for o in objects if any(e.backup for e in o)],
            [o.index for o in objects if any(e.setting for e in o)],
        ]
        if list_type == LIST_LENGTHS:
            values = [len(x) for x in lists]
        elif LIST_ALL <= list_type <= LIST_SETTINGS:
            values = lists[list_type - 1]
        else:
            return [self._error(A.VALUE_RANGE_EXCEEDED)]
        # the list type goes first; fragments are cut at whole UINT16 values
        payload = struct.pack(f"<{len(values) + 1}H", list_type, *values)
        return self._fragments(OD_LIST_RES, payload, unit=2)

    def _object_description(self, index: int) -> list[bytes]:
        obj = self.drive.device.dictionary.get(index)
        if obj is None:
            return [self._error(A.OBJECT_DOES_NOT_EXIST)]
        payload = struct.pack("<HHBB", index, _data_type(obj), obj.max_subindex, OBJECT_CODES[obj.object_code])
        return self._fragments(OBJECT_DESC_RES, payload + _name(obj.name))

    def _entry_description(self, index: int, sub: int, info: int) -> list[bytes]:
        obj = self.drive.device.dictionary.get(index)
        if obj is None:
            return [self._error(A.OBJECT_DOES_NOT_EXIST)]
        e = obj.entries.get(sub)
        if e is None:
            return [self._error(A.SUBINDEX_DOES_NOT_EXIST)]
        values, info_out = self._values(e, info)
        dtype = e.datatype.code if e.datatype is not None else 0
        payload = struct.pack("<HBBHHH", index, sub, info_out, dtype, e.bit_size, object_access(e))
        return self._fragments(ENTRY_DESC_RES, payload + values + _name(e.name))

    @staticmethod
    def _values(e: Entry, info: int) -> tuple[bytes, int]:
        """Default, minimum and maximum where asked for and known (numeric entries only); the unit type (bit 3)
        is never sent. Returns the value octets and the value info bits that say which are present."""
        out = b""
        info_out = info & VALUE_INFO_ALWAYS
        numeric = e.datatype is not None and e.datatype.bits is not None and e.datatype.kind in (
            Kind.UNSIGNED, Kind.SIGNED, Kind.REAL, Kind.BOOL, Kind.BITS)
        if not numeric:
            return out, info_out
        candidates = ((VALUE_INFO_DEFAULT, e.default_value), (VALUE_INFO_MINIMUM, e.minimum),
                      (VALUE_INFO_MAXIMUM, e.maximum))
        for bit, value in candidates:
            if info & bit and value is not None:
                try:
                    out += e.encode(value)
                except (EcatToolError, ValueError, OverflowError, TypeError):  # a limit the type cannot hold: left out
                    continue
                info_out |= bit
        return out, info_out
