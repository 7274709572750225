"""The served bus under a wrong master, in process (issue 28, item 4): sync managers and FMMUs reach only the
memory the ESC has, writes outside it are ignored and never grow it, a sync manager an earlier master left never
takes the registers or another SM's area, and the mailbox bounds what a master can make the slave hold. The same
rules on the wire, with SOEM after a burst of hostile frames: tests/wire/test_wire_hostile.py."""

from __future__ import annotations

import struct

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from ecattool.od.model import EcState
from ecattool.sim import Drive
from ecattool.sim.bus import Bus, Cmd, Datagram
from ecattool.sim.bus.loop import Loop
from ecattool.sim.esc import registers as R
from ecattool.sim.esc.mapping import segments
from ecattool.sim.mailbox import MailboxServer
from ecattool.sim.mailbox import foe as F
from ecattool.sim.mailbox.coe import MAX_SDO_BYTES
from ecattool.sim.mailbox.server import MAX_QUEUED_REPLIES
from ecattool.sim.slave import VirtualSlave
from tests.wire.test_wire_slave import ST, MiniMaster, _fmmu, _sm

END = R.PROCESS_RAM + 8192  # the ESC's memory: registers and 8 KiB of process RAM (SII word 0x0006 says 8)


@pytest.fixture
def hdt() -> MiniMaster:
    return MiniMaster(VirtualSlave.from_drive(Drive.from_profile("hdt")))


def _bwr(m: MiniMaster, addr: int, data: bytes) -> int:
    return m.loop.one(Datagram.make(Cmd.BWR, 0, addr, data)).wkc


def test_the_memory_is_what_the_esc_says_and_never_grows(hdt: MiniMaster) -> None:
    esc = hdt.slave.esc
    assert len(esc.mem) == END and esc.mem[R.RAM_SIZE] * 1024 + R.PROCESS_RAM == END
    # a buffered output SM whose area runs past the end: not activated, its bytes are plain memory
    assert hdt.wr(R.SM + 16, _sm(END - 0x100, 0x400, 0x64)) == 1
    assert hdt.wr(END - 0x100, b"\xAA" * 0x400) == 1  # what fits is written, the rest is not there
    assert len(esc.mem) == END and esc.mem[END - 0x100:END] == b"\xAA" * 0x100
    # past the end: ignored, the working counter of any addressed access, reads give zeros
    assert hdt.wr(END + 0x10, b"\x55" * 16) == 1 and len(esc.mem) == END
    assert hdt.rd(0xFFF0, 16) == (bytes(16), 1)
    assert len(esc.mem) == END


def test_an_sm_over_the_registers_is_not_activated(hdt: MiniMaster) -> None:
    """The frame that made every later SOEM find 0 slaves: a broadcast enabling SM4 at 0x0000, 0x1000 octets."""
    esc = hdt.slave.esc
    assert _bwr(hdt, R.SM + 4 * R.SM_SIZE, _sm(0x0000, 0x1000, 0x26)) == 1
    assert esc.sm(4).enabled and not esc.sm(4).active
    assert _bwr(hdt, R.AL_CONTROL, struct.pack("<H", 0x11)) == 1  # a register write still reaches the register
    assert hdt.rd(R.TYPE, 1) == (bytes([0x11]), 1)
    assert hdt.rd(R.STATION_ADDRESS, 2) == (struct.pack("<H", ST), 1)
    hdt.mailbox_config()
    assert hdt.al(2) == (0x02, 0)  # and the slave still comes up
    assert hdt.upload(0x1018, 1) == hdt.slave.drive.sdo_upload(0x1018, 1)


def test_lower_numbered_sm_serves_where_areas_overlap() -> None:
    class Area:
        def __init__(self, start: int, length: int) -> None:
            self.start, self.length, self.active = start, length, True

    sms = [Area(0x1000, 0x80), Area(0x1080, 0x80), Area(0x1100, 4), Area(0x1400, 4), Area(0x1000, 0x800)]
    assert segments(sms, 0x1000, 0x100) == ((0x1000, 0x1080, 0), (0x1080, 0x1100, 1))
    assert segments(sms, 0x10F0, 0x20) == ((0x10F0, 0x1100, 1), (0x1100, 0x1104, 2), (0x1104, 0x1110, 4))
    assert segments(sms, 0x3000, 4) == ((0x3000, 0x3004, None),)


def test_leftover_sm4_to_sm7_never_break_a_master_that_sets_up_sm0_to_sm3(hdt: MiniMaster) -> None:
    """SOEM resets only SM0-SM3 and FMMU0-FMMU2: an earlier master's SM4-SM7 over the mailbox and process
    areas stay, and the mailbox, the state changes and the process data still work with full working counters."""
    left = b"".join(_sm(0x1000, 0x800, control) for control in (0x20, 0x22, 0x64, 0x26))
    assert hdt.wr(R.SM + 4 * R.SM_SIZE, left) == 1
    assert hdt.wr(R.SM, bytes(4 * R.SM_SIZE)) == 1  # SOEM's reset of SM0-SM3
    hdt.mailbox_config()
    assert hdt.al(2) == (0x02, 0)
    for index, sub in ((0x1018, 1), (0x1018, 2), (0x6060, 0)):
        assert hdt.upload(index, sub) == hdt.slave.drive.sdo_upload(index, sub)
    out_len, in_len = 28, 20  # HDT's default assignment (1600h + 1A00h)
    hdt.wr(R.SM + 16, _sm(0x1100, out_len, 0x64) + _sm(0x1400, in_len, 0x20))
    hdt.wr(R.FMMU, _fmmu(0x0, out_len, 0x1100, 2) + _fmmu(out_len, in_len, 0x1400, 1))
    assert hdt.al(4) == (0x04, 0)
    assert hdt.al(8) == (0x08, 0)
    lrw = hdt.loop.one(Datagram.logical(Cmd.LRW, 0, struct.pack("<H", 6) + bytes(out_len - 2 + in_len)))
    assert lrw.wkc == 3  # outputs written (+2) and inputs read (+1): the leftover SMs take nothing
    assert hdt.slave.drive.value(0x6040) == 6


def test_an_fmmu_past_the_memory_serves_nothing(hdt: MiniMaster) -> None:
    esc = hdt.slave.esc
    assert hdt.wr(R.FMMU + 3 * R.FMMU_SIZE, _fmmu(0x8000, 0x40, END - 0x10, 3)) == 1
    d = hdt.loop.one(Datagram.logical(Cmd.LRW, 0x8000, b"\x77" * 0x40))
    assert d.wkc == 0 and len(esc.mem) == END and esc.mem[END - 0x10:] == bytes(0x10)
    assert hdt.wr(R.FMMU + 3 * R.FMMU_SIZE, _fmmu(0x8000, 0x10, END - 0x10, 3)) == 1  # fits: served
    d = hdt.loop.one(Datagram.logical(Cmd.LRW, 0x8000, b"\x77" * 0x10))
    assert d.wkc == 3 and esc.mem[END - 0x10:] == b"\x77" * 0x10


# --- the mailbox's own limits ------------------------------------------------------------------------


def _mbx(mtype: int, data: bytes, counter: int = 1) -> bytes:
    return struct.pack("<HHBB", len(data), 0, 0, mtype | (counter << 4)) + data


def _coe(data: bytes, counter: int = 1) -> bytes:
    return _mbx(3, struct.pack("<H", 2 << 12) + data, counter)


def _preop(profile: str) -> Drive:
    drive = Drive.from_profile(profile)
    drive.request_state(EcState.PREOP)
    return drive


def test_a_segmented_download_of_4_gib_is_refused_at_the_initiate() -> None:
    server = MailboxServer(_preop("hdt"), 128, 128)
    # 100Ah (a STRING the HDT profile lets a master write in PRE-OP) announcing 4 GiB - 1: more than any
    # transfer may hold (out of memory). (No built-in profile has complete access: a complete access initiate is
    # refused with 0601 0004h before its size is looked at.)
    server.handle(_coe(struct.pack("<BHBI", 0x21, 0x100A, 0, 0xFFFFFFFF) + bytes(8)))
    reply = server.pending()
    assert reply is not None and reply[8] == 0x80 and struct.unpack_from("<I", reply, 12)[0] == 0x05040005
    assert server.sdo._transfer is None
    # the cap itself is allowed to start (and then bounded by what was announced)
    server.handle(_coe(struct.pack("<BHBI", 0x21, 0x100A, 0, MAX_SDO_BYTES) + bytes(8), 2))
    reply = server.pending()
    assert reply is not None and reply[8] & 0xE0 == 0x60 and server.sdo._transfer is not None


@pytest.mark.parametrize("index, sub, code", [(0x1008, 0, 0x06010002), (0x5FFE, 0, 0x06020000),
                                              (0x1600, 0, 0x06010004)])
def test_a_segmented_download_to_what_no_data_can_write_is_refused_at_the_initiate(index: int, sub: int,
                                                                                    code: int) -> None:
    """Issue 37.6: a read-only object (1008h device name) or a missing one gets its abort at the initiate, as a
    slave stack answers; the simulator used to take up to 1 MiB of segments before aborting."""
    server = MailboxServer(_preop("hdt"), 128, 128)
    ca = 0x10 if index == 0x1600 else 0  # 1600h by complete access, which the HDT drive does not support
    server.handle(_coe(struct.pack("<BHBI", 0x21 | ca, index, sub, MAX_SDO_BYTES) + bytes(8)))
    reply = server.pending()
    assert reply is not None and reply[8] == 0x80 and struct.unpack_from("<HBI", reply, 9) == (index, sub, code)
    assert server.sdo._transfer is None


def test_a_transfer_a_master_left_is_dropped_at_init(hdt: MiniMaster) -> None:
    hdt.mailbox_config()
    assert hdt.al(2) == (0x02, 0)
    # a segmented download started and never finished (6081h profile velocity: UDINT, writable in PRE-OP; the
    # initiate announces its 4 octets and carries none)
    big = struct.pack("<HBHBI", 0x2000, 0x21, 0x6081, 0, 4)
    assert hdt.send_mbx(big) == 1 and hdt.recv_mbx() is not None
    assert hdt.slave.mailbox.sdo._transfer is not None
    assert hdt.al(1) == (0x01, 0)
    assert hdt.slave.mailbox.sdo._transfer is None


def test_an_foe_write_is_bounded_by_what_the_drive_takes() -> None:
    drive = _preop("technosoft-ipos")
    server = MailboxServer(drive, 1024, 128)
    server.handle(_mbx(4, struct.pack("<BBI", F.WRITE, 0, 0) + b"FOESW_big"))
    assert server.pending() is not None  # ACK 0
    room = 1024 - 6 - F.FOE_OVERHEAD
    packet, code = 0, 0
    for packet in range(1, F.MAX_FILE_BYTES // room + 3):  # bounded: one packet past the limit
        server.handle(_mbx(4, struct.pack("<BBI", F.DATA, 0, packet) + bytes(room), packet % 7 + 1))
        reply = server.pending()
        assert reply is not None
        if reply[6] == F.ERROR:
            code = struct.unpack_from("<I", reply, 8)[0]
            break
    assert code == F.DISK_FULL and packet == F.MAX_FILE_BYTES // room + 1
    assert server.foe._write is None  # dropped


def test_out_of_order_foe_data_ends_the_write() -> None:
    server = MailboxServer(_preop("technosoft-ipos"), 128, 128)
    server.handle(_mbx(4, struct.pack("<BBI", F.WRITE, 0, 0) + b"FOESW_x"))
    server.pending()
    server.handle(_mbx(4, struct.pack("<BBI", F.DATA, 0, 5) + bytes(10), 2))
    reply = server.pending()
    assert reply is not None and reply[6] == F.ERROR and struct.unpack_from("<I", reply, 8)[0] == F.PACKET_NUMBER_WRONG
    assert server.foe._write is None


def test_replies_nobody_reads_are_bounded() -> None:
    server = MailboxServer(_preop("hdt"), 128, 128)
    for i in range(3 * MAX_QUEUED_REPLIES):
        server.handle(_coe(struct.pack("<BHBI", 0x40, 0x1018, 1, 0), i % 7 + 1))
    assert len(server._replies) == MAX_QUEUED_REPLIES


def test_bad_mailbox_headers_get_mailbox_errors() -> None:
    server = MailboxServer(_preop("hdt"), 128, 128)
    for raw in (b"\x01\x02", struct.pack("<HHBB", 200, 0, 0, 0x13) + bytes(10), _mbx(0x0F, b"\x00" * 8)):
        server.handle(raw)
        reply = server.pending()
        assert reply is not None and reply[5] & 0x0F == 0  # mailbox type 0: error
    assert server.pending() is None


def test_a_bus_of_several_slaves_after_a_leftover_sm_over_the_registers() -> None:
    slaves = [VirtualSlave.from_drive(Drive.from_profile(p)) for p in ("hdt", "technosoft-ipos")]
    loop = Loop(Bus([s.esc for s in slaves]))
    assert loop.one(Datagram.make(Cmd.BWR, 0, R.SM + 4 * R.SM_SIZE, _sm(0x0000, 0x1000, 0x26))).wkc == 2
    assert loop.one(Datagram.make(Cmd.BRD, 0, R.TYPE, 1)).wkc == 2  # what SOEM counts slaves with


# --- any sequence of accesses -------------------------------------------------------------------------

_ACCESS = st.tuples(
    st.sampled_from(["wr", "rd", "sm", "fmmu", "lrw"]),
    st.integers(0, 0xFFFF),
    st.binary(min_size=1, max_size=48),
)


@settings(max_examples=60, deadline=None)
@given(st.lists(_ACCESS, min_size=1, max_size=25))
def test_no_sequence_of_accesses_grows_the_memory_or_breaks_the_registers(accesses: list) -> None:
    slave = VirtualSlave.from_drive(Drive.from_profile("hdt"))
    loop = Loop(Bus([slave.esc]))
    for kind, addr, data in accesses:
        if kind == "wr":
            loop.one(Datagram.make(Cmd.BWR, 0, addr, data))
        elif kind == "rd":
            d = loop.one(Datagram.make(Cmd.BRD, 0, addr, len(data)))
            assert len(d.data) == len(data)
        elif kind == "sm":
            loop.one(Datagram.make(Cmd.BWR, 0, R.SM + R.SM_SIZE * (addr % 8), (data * 8)[:8]))
        elif kind == "fmmu":
            loop.one(Datagram.make(Cmd.BWR, 0, R.FMMU + R.FMMU_SIZE * (addr % 8), (data * 16)[:16]))
        else:
            loop.one(Datagram.logical(Cmd.LRW, addr * 0x10001, data))
        assert len(slave.esc.mem) == END
    # whatever was left, the registers answer: the type, and a station address written and read back
    assert loop.one(Datagram.make(Cmd.BRD, 0, R.TYPE, 1)).wkc == 1
    assert loop.one(Datagram.make(Cmd.APWR, 0, R.STATION_ADDRESS, struct.pack("<H", 0x1234))).wkc == 1
    assert bytes(loop.one(Datagram.make(Cmd.FPRD, 0x1234, R.STATION_ADDRESS, 2)).data) == struct.pack("<H", 0x1234)

