"""A served slave that misbehaves on purpose: the test hook of ``ecattool sim serve --misbehave NAME`` (a hidden
option), with which the hostile-slave wire test (tests/wire/test_wire_hostile_slave.py) checks that no answer of a slave
ends ecattool, or makes it hang or report what it did not read.

Each misbehaviour is what a broken or hostile slave has been seen to do (issue 37); it is switched on for every
slave served, before serving starts, by replacing one method of the slave's mailbox or EEPROM content, or through
the transport's frame hook. Nothing here is used unless the option is given.
"""

from __future__ import annotations

import struct
from collections.abc import Callable
from typing import TYPE_CHECKING

from ecattool.errors import InputError
from ecattool.sim.bus.frame import DG_HEAD_SIZE, ETH_HEADER, FrameError, carries_datagrams, datagram_heads

if TYPE_CHECKING:
    from ecattool.sim.bus.loop import FrameFault
    from ecattool.sim.bus.serve import Served
    from ecattool.sim.slave import VirtualSlave

#: name -> what the slave does
MISBEHAVIOURS = {
    "upload-4gib": "every SDO upload is answered as a normal transfer announcing 0xFFFFFFFF octets",
    "upload-endless": "every SDO upload is answered with segments that never end",
    "reply-truncated": "every mailbox reply is cut to 4 octets of data (its header says so)",
    "reply-empty": "every mailbox reply carries no data (length 0)",
    "wrong-wkc": "every datagram comes back with a working counter one higher than the slaves counted",
    "sii-blank": "the SII EEPROM is blank (every word 0xFFFF)",
    "sii-no-end": "the SII category chain has no end marker: zero words follow the last category to 4 KiB",
    "vanish": "the slave stops answering for VANISH_S after each first mailbox request of a bus init",
}
#: the octets an endless upload announces (fits SOEM's 256-octet buffer, so SOEM goes segmented)
ENDLESS_ANNOUNCED = 200
#: how long a vanished slave stays away (then it answers again, as a slave whose link came back)
VANISH_S = 2.5
#: the EEPROM a chain without end marker fills
SII_NO_END_BYTES = 4096


def _upload_4gib(slave: "VirtualSlave") -> None:
    sdo = slave.mailbox.sdo
    handle = sdo.handle

    def hostile(data: bytes) -> list[bytes]:
        if len(data) >= 10 and data[2] >> 5 == 2:  # an upload initiate request
            index, sub = struct.unpack_from("<HB", data, 3)
            return [struct.pack("<HBHBI", 3 << 12, (2 << 5) | 0x01, index, sub, 0xFFFFFFFF) + bytes(8)]
        return handle(data)

    sdo.handle = hostile  # type: ignore[method-assign]


def _upload_endless(slave: "VirtualSlave") -> None:
    sdo = slave.mailbox.sdo
    handle = sdo.handle

    def hostile(data: bytes) -> list[bytes]:
        if len(data) >= 10 and data[2] >> 5 == 2:  # initiate: announces 200 octets, sends 4 of them
            index, sub = struct.unpack_from("<HB", data, 3)
            return [struct.pack("<HBHBI", 3 << 12, (2 << 5) | 0x01, index, sub, ENDLESS_ANNOUNCED) + b"\xAA" * 4]
        if len(data) >= 3 and data[2] >> 5 == 3:  # a segment request: a full segment, never the last
            room = max(7, sdo.in_size - 6 - 3)
            return [struct.pack("<HB", 3 << 12, data[2] & 0x10) + b"\x55" * room]
        return handle(data)

    sdo.handle = hostile  # type: ignore[method-assign]


def _reply_cut(slave: "VirtualSlave", keep: int) -> None:
    mailbox = slave.mailbox
    pending = mailbox.pending

    def hostile() -> bytes | None:
        reply = pending()
        if reply is None:
            return None
        return struct.pack("<H", keep) + reply[2:6] + reply[6:6 + keep]

    mailbox.pending = hostile  # type: ignore[method-assign]


def _sii(slave: "VirtualSlave", blank: bool) -> None:
    data = slave.esc.eeprom.data
    if blank:
        data[:] = b"\xff" * len(data)
        return
    end = _end_marker(bytes(data))
    data[end:] = bytes(SII_NO_END_BYTES - end)


def _end_marker(data: bytes) -> int:
    """The byte offset of the category chain's end marker (0xFFFF), found by walking the chain."""
    offset = 128
    while offset + 4 <= len(data):
        if int.from_bytes(data[offset:offset + 2], "little") == 0xFFFF:
            return offset
        offset += 4 + 2 * int.from_bytes(data[offset + 2:offset + 4], "little")
    return min(offset, len(data))


def _vanish(slaves: list["VirtualSlave"]) -> "FrameFault":
    import time

    #: when the slave went away (0: it is there); it goes at a mailbox request after a reset to INIT
    gone = [0.0]
    armed = [True]
    for slave in slaves:
        mailbox = slave.mailbox
        handle, reset = mailbox.handle, mailbox.reset

        def first(frame_bytes: bytes, handle: Callable[[bytes], None] = handle) -> None:
            handle(frame_bytes)
            if armed[0]:
                armed[0], gone[0] = False, time.monotonic()

        def rearm(reset: Callable[[], None] = reset) -> None:
            reset()
            armed[0] = True

        mailbox.handle = first  # type: ignore[method-assign]
        mailbox.reset = rearm  # type: ignore[method-assign]

    def fault(raw: bytes) -> tuple[bytes | None, bool]:
        if gone[0] and time.monotonic() - gone[0] < VANISH_S:
            return None, True
        gone[0] = 0.0  # back (until the next mailbox request after a reset to INIT)
        return raw, True

    return fault


def _wrong_wkc(raw: bytes) -> tuple[bytes | None, bool]:
    buf = bytearray(raw)
    if not carries_datagrams(buf):
        return raw, True
    try:
        heads = datagram_heads(buf, ETH_HEADER)
    except FrameError:
        return raw, True
    for pos, _cmd, _index, _address, dlen, _irq, wkc in heads:
        at = pos + DG_HEAD_SIZE + (dlen & 0x7FF)
        struct.pack_into("<H", buf, at, (wkc + 1) & 0xFFFF)
    return bytes(buf), True


def apply(name: str, served: list["Served"]) -> "FrameFault | None":
    """Switch misbehaviour ``name`` on for every slave of ``served``; returns the frame hook it needs (or None)."""
    if name not in MISBEHAVIOURS:
        raise InputError(f"unknown misbehaviour {name!r} (one of {', '.join(MISBEHAVIOURS)})")
    slaves = [s.slave for s in served]
    for slave in slaves:
        if name == "upload-4gib":
            _upload_4gib(slave)
        elif name == "upload-endless":
            _upload_endless(slave)
        elif name in ("reply-truncated", "reply-empty"):
            _reply_cut(slave, 4 if name == "reply-truncated" else 0)
        elif name in ("sii-blank", "sii-no-end"):
            _sii(slave, name == "sii-blank")
    if name == "vanish":
        return _vanish(slaves)
    if name == "wrong-wkc":
        return _wrong_wkc
    return None
