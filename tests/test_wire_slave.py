"""A drive of the simulator as a virtual slave, driven frame by frame through the in-process loop the way SOEM
drives it (issue 13, item 4): mailbox SM configuration checked at INIT -> PRE-OP, CoE through SM0/SM1 with
repeat, process data SMs and FMMUs checked against the PDO assignment at PRE-OP -> SAFE-OP with the families'
AL codes, the error indication until acknowledged, process data through SM2/SM3, DC activation."""

from __future__ import annotations

import struct

import pytest

from ecattool.errors import SdoAbort
from ecattool.od.model import EcState
from ecattool.sim import Drive
from ecattool.sim.bus import Bus, Cmd, Datagram
from ecattool.sim.bus.loop import Loop
from ecattool.sim.esc import registers as R
from ecattool.sim.slave import VirtualSlave

ST = 0x1001


def _sm(start: int, length: int, control: int, enable: int = 1) -> bytes:
    return struct.pack("<HHBBBB", start, length, control, 0, enable, 0)


def _fmmu(logical: int, length: int, physical: int, kind: int) -> bytes:
    return struct.pack("<IHBBHBBBxxx", logical, length, 0, 7, physical, 0, kind, 1)


class MiniMaster:
    """Just enough master to drive one slave: register access, AL requests, CoE expedited uploads."""

    def __init__(self, slave: VirtualSlave) -> None:
        self.slave = slave
        self.loop = Loop(Bus([slave.esc]))
        self.counter = 0
        assert self.loop.one(Datagram.make(Cmd.APWR, 0, R.STATION_ADDRESS, struct.pack("<H", ST))).wkc == 1
        words = slave.esc.eeprom.words(0x18, 4)  # SII: standard mailbox offsets and sizes
        self.mbx_out, self.mbx_out_len, self.mbx_in, self.mbx_in_len = words

    def wr(self, addr: int, data: bytes) -> int:
        return self.loop.one(Datagram.make(Cmd.FPWR, ST, addr, data)).wkc

    def rd(self, addr: int, n: int) -> tuple[bytes, int]:
        d = self.loop.one(Datagram.make(Cmd.FPRD, ST, addr, n))
        return bytes(d.data), d.wkc

    def al(self, state: int) -> tuple[int, int]:
        """Request ``state`` (with bit 4 = acknowledge); AL status and status code afterwards."""
        self.wr(R.AL_CONTROL, struct.pack("<H", state))
        status, _ = self.rd(R.AL_STATUS, 6)
        return int.from_bytes(status[:2], "little"), int.from_bytes(status[4:6], "little")

    def mailbox_config(self) -> None:
        self.wr(R.SM, _sm(self.mbx_out, self.mbx_out_len, 0x26) + _sm(self.mbx_in, self.mbx_in_len, 0x22))

    def send_mbx(self, payload: bytes, mtype: int = 3) -> int:
        self.counter = self.counter % 7 + 1
        frame = struct.pack("<HHBB", len(payload), 0, 0, (self.counter << 4) | mtype) + payload
        return self.wr(self.mbx_out, frame.ljust(self.mbx_out_len, b"\x00"))

    def recv_mbx(self) -> bytes | None:
        data, wkc = self.rd(self.mbx_in, self.mbx_in_len)
        if wkc == 0:
            return None
        (length,) = struct.unpack_from("<H", data)
        return data[6:6 + length]

    def upload(self, index: int, sub: int) -> bytes:
        """CoE SDO upload (expedited or normal in one frame); raises SdoAbort with the slave's code."""
        assert self.send_mbx(struct.pack("<HBHB4x", 0x2000, 0x40, index, sub)) == 1
        reply = self.recv_mbx()
        assert reply is not None
        cmd = reply[2]
        if cmd == 0x80:
            raise SdoAbort(index, sub, struct.unpack_from("<I", reply, 6)[0])
        if cmd & 0x02:  # expedited: size in bits 2..3 when bit 0 says so
            return reply[6:10][:4 - ((cmd >> 2) & 3) if cmd & 1 else 4]
        (size,) = struct.unpack_from("<I", reply, 6)
        return reply[10:10 + size]


@pytest.fixture
def hdt() -> MiniMaster:
    return MiniMaster(VirtualSlave.from_drive(Drive.from_profile("hdt")))


def test_sii_and_identity_match_the_drive(hdt: MiniMaster) -> None:
    ident = hdt.slave.drive.identity()
    assert hdt.slave.esc.eeprom.words(8, 6) == [ident.vendor_id & 0xFFFF, ident.vendor_id >> 16,
                                                ident.product_code & 0xFFFF, ident.product_code >> 16,
                                                ident.revision & 0xFFFF, ident.revision >> 16]
    assert hdt.mbx_out_len == 128 and hdt.mbx_out >= 0x1000


def test_mailbox_configuration_checked_at_preop_and_error_needs_ack(hdt: MiniMaster) -> None:
    # SM0 configured as a read mailbox: PRE-OP refused with 0x0016, error indication set
    hdt.wr(R.SM, _sm(hdt.mbx_out, hdt.mbx_out_len, 0x22) + _sm(hdt.mbx_in, hdt.mbx_in_len, 0x22))
    assert hdt.al(2) == (0x11, 0x0016)
    hdt.mailbox_config()
    assert hdt.al(2) == (0x11, 0x0016)  # not acknowledged: the request is ignored
    assert hdt.al(2 | 0x10) == (0x02, 0)
    assert hdt.slave.drive.state() is EcState.PREOP
    assert hdt.al(8) == (0x12, 0x0011)  # PRE-OP -> OP is not a transition: the drive's code
    assert hdt.al(0x11) == (0x01, 0)  # acknowledged back to INIT


def test_coe_upload_agrees_with_the_drive_and_repeat(hdt: MiniMaster) -> None:
    hdt.mailbox_config()
    assert hdt.al(2) == (0x02, 0)
    drive = hdt.slave.drive
    for index, sub in ((0x1018, 1), (0x1018, 2), (0x1C12, 0), (0x6060, 0), (0x6064, 0)):
        assert hdt.upload(index, sub) == drive.sdo_upload(index, sub)
    with pytest.raises(SdoAbort) as got:
        hdt.upload(0x5FFF, 0)
    with pytest.raises(SdoAbort) as want:
        drive.sdo_upload(0x5FFF, 0)
    assert got.value.code == want.value.code
    # a lost read: the master toggles the repeat request and gets the same answer again
    assert hdt.send_mbx(struct.pack("<HBHB4x", 0x2000, 0x40, 0x1018, 1)) == 1
    first = hdt.recv_mbx()
    status, _ = hdt.rd(R.SM + 8 + 5, 2)
    hdt.wr(R.SM + 8 + 5, bytes([status[0], status[1] ^ 0x02]))  # SOEM writes status + activate, toggled
    ack, _ = hdt.rd(R.SM + 8 + 7, 1)
    assert ack[0] & 0x02 == (status[1] ^ 0x02) & 0x02
    assert hdt.recv_mbx() == first and first is not None


def _pd_config(m: MiniMaster, out_len: int, in_len: int) -> None:
    m.wr(R.SM + 16, _sm(0x1100, out_len, 0x64) + _sm(0x1400, in_len, 0x20))
    m.wr(R.FMMU, _fmmu(0x0, out_len, 0x1100, 2) + _fmmu(out_len, in_len, 0x1400, 1))


def test_process_data_checked_against_the_pdo_assignment(hdt: MiniMaster) -> None:
    hdt.mailbox_config()
    hdt.al(2)
    drive = hdt.slave.drive
    out_len, in_len = 28, 20  # HDT's default assignment (1600h + 1A00h)
    _pd_config(hdt, out_len - 2, in_len)
    assert hdt.al(4) == (0x12, 0x001D)
    assert drive.state() is EcState.PREOP and hdt.slave.refusals[-1].code == 0x001D
    _pd_config(hdt, out_len, in_len + 4)
    assert hdt.al(4 | 0x10) == (0x12, 0x001E)
    hdt.wr(R.SM + 16, _sm(0x1100, out_len, 0x64) + _sm(0x1400, in_len, 0x20))
    hdt.wr(R.FMMU + 16, bytes(16))  # no input FMMU
    assert hdt.al(4 | 0x10) == (0x12, 0x001E)
    _pd_config(hdt, out_len, in_len)
    assert hdt.al(4 | 0x10) == (0x04, 0)
    assert drive.process_image_sizes() == (out_len, in_len)
    lrw = hdt.loop.one(Datagram.logical(Cmd.LRW, 0, out_len + in_len))
    assert lrw.wkc == 3
    statusword = int.from_bytes(lrw.data[out_len:out_len + 2], "little")
    assert statusword == drive.sdo_upload(0x6041, 0)[0] | drive.sdo_upload(0x6041, 0)[1] << 8
    assert hdt.al(8) == (0x08, 0)
    # controlword 6 (shutdown) through the outputs: ready to switch on comes back in the inputs
    outputs = bytearray(out_len)
    outputs[0:2] = struct.pack("<H", 6)
    for _ in range(2):
        lrw = hdt.loop.one(Datagram.logical(Cmd.LRW, 0, bytes(outputs) + bytes(in_len)))
    assert lrw.wkc == 3 and drive.value(0x6040) == 6
    assert int.from_bytes(lrw.data[out_len:out_len + 2], "little") & 0x6F == 0x21


def test_dc_activation_reaches_the_drive(hdt: MiniMaster) -> None:
    hdt.mailbox_config()
    hdt.al(2)
    now = int.from_bytes(hdt.rd(R.DC_SYSTEM_TIME, 8)[0], "little")
    hdt.wr(R.DC_SYNC0_CYCLE, struct.pack("<I", 1_000_000))
    hdt.wr(R.DC_START_TIME, struct.pack("<Q", (now // 1_000_000 + 100) * 1_000_000 + 250_000))
    hdt.wr(R.DC_ACTIVATION, b"\x03")
    dc = [e.data for e in hdt.slave.drive.events if e.kind == "dc"]
    assert dc[-1] == {"assign_activate": 0x0300, "sync0_cycle_ns": 1_000_000, "sync0_shift_ns": 250_000}
    hdt.wr(R.DC_ACTIVATION, b"\x00")
    assert [e.data for e in hdt.slave.drive.events if e.kind == "dc"][-1]["assign_activate"] == 0
