"""A drive of the simulator as a virtual slave, driven frame by frame through the in-process loop the way SOEM
drives it (issue 13, item 4): mailbox SM configuration checked at INIT -> PRE-OP, CoE through SM0/SM1 with
repeat, process data SMs and FMMUs checked against the PDO assignment at PRE-OP -> SAFE-OP with the families'
AL codes, the error indication until acknowledged, process data through SM2/SM3, DC activation."""

from __future__ import annotations

import struct
from collections.abc import Callable

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

    def __init__(self, slave: VirtualSlave, clock: Callable[[], int] | None = None) -> None:
        self.slave = slave
        self.loop = Loop(Bus([slave.esc]) if clock is None else Bus([slave.esc], clock=clock))
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
    # an empty string (HDT's 1008h device name) is a normal upload of size 0: an expedited reply cannot say 0 bytes
    assert drive.sdo_upload(0x1008, 0) == b"" and hdt.upload(0x1008, 0) == b""
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


class FakeTime:
    """The bus's host clock (ns), advanced by the test: the watchdog is checked without waiting."""

    def __init__(self) -> None:
        self.ns = 10_000_000_000

    def __call__(self) -> int:
        return self.ns

    def ms(self, n: float) -> None:
        self.ns += int(n * 1_000_000)


def _to_op(m: MiniMaster, out_len: int = 28, in_len: int = 20) -> bytearray:
    """HDT (default assignment) to OP with one process data cycle; the outputs (controlword 0)."""
    m.mailbox_config()
    assert m.al(2) == (0x02, 0)
    _pd_config(m, out_len, in_len)
    assert m.al(4) == (0x04, 0)
    outputs = bytearray(out_len)
    assert m.loop.one(Datagram.logical(Cmd.LRW, 0, bytes(outputs) + bytes(in_len))).wkc == 3
    assert m.al(8) == (0x08, 0)
    return outputs


def _cycle(m: MiniMaster, outputs: bytes, in_len: int = 20) -> int:
    return m.loop.one(Datagram.logical(Cmd.LRW, 0, bytes(outputs) + bytes(in_len))).wkc


def test_process_data_watchdog_takes_the_drive_out_of_op_with_0x001b() -> None:
    """ET1100 watchdog: (0x0400 + 2) x 40 ns x 0x0420, default 2498 / 1000 = 100 ms (HDT manual 3.04),
    triggered by each complete write of SM2 (control bit 6). Expired in OP: SAFE-OP + error + 0x001B, the
    status 0x0440 reads 0 and the counter 0x0442 counts; the master acknowledges and goes back to OP."""
    t = FakeTime()
    m = MiniMaster(VirtualSlave.from_drive(Drive.from_profile("hdt")), clock=t)
    outputs = _to_op(m)
    wd = m.rd(R.WD_DIVIDER, 2)[0] + m.rd(R.WD_TIME_PD, 2)[0]
    assert struct.unpack("<HH", wd) == (2498, 1000)
    for _ in range(5):  # cycles 99 ms apart keep it alive
        t.ms(99)
        assert _cycle(m, outputs) == 3
    assert m.rd(R.WD_STATUS_PD, 2)[0] == b"\x01\x00"
    assert m.al(8) == (0x08, 0)
    t.ms(100.001)  # just over 100 ms since the last write of SM2: the next frame finds it expired
    status, code = m.al(8)  # a request for OP without acknowledge is ignored while the error shows
    assert (status, code) == (0x14, 0x001B)
    assert m.slave.drive.state() is EcState.SAFEOP
    assert m.rd(R.WD_STATUS_PD, 2)[0] == b"\x00\x00" and m.rd(R.WD_COUNTER_PD, 1)[0] == b"\x01"
    reason = [e.data for e in m.slave.drive.events if e.kind == "state"][-1]
    assert reason["al_status"] == 0x001B and reason["reason"] == "sync manager watchdog"
    assert _cycle(m, outputs) == 3  # SAFE-OP: the SM2 write is taken (and triggers), the drive ignores it
    assert m.al(4 | 0x10) == (0x04, 0)  # acknowledged
    assert m.al(8) == (0x08, 0) and _cycle(m, outputs) == 3
    m.wr(R.WD_COUNTER_PD, b"\x00")  # a write clears the counter
    assert m.rd(R.WD_COUNTER_PD, 1)[0] == b"\x00"


def test_process_data_watchdog_time_and_divider_are_the_masters() -> None:
    t = FakeTime()
    m = MiniMaster(VirtualSlave.from_drive(Drive.from_profile("hdt")), clock=t)
    outputs = _to_op(m)
    m.wr(R.WD_TIME_PD, struct.pack("<H", 0))  # 0 disables it
    _cycle(m, outputs)
    t.ms(5000)
    assert m.al(8) == (0x08, 0) and m.rd(R.WD_STATUS_PD, 2)[0] == b"\x01\x00"
    m.wr(R.WD_DIVIDER, struct.pack("<H", 498))  # 20 us
    m.wr(R.WD_TIME_PD, struct.pack("<H", 1000))  # 20 ms
    _cycle(m, outputs)
    t.ms(19)
    assert m.al(8) == (0x08, 0)
    _cycle(m, outputs)
    t.ms(21)
    assert m.al(8) == (0x14, 0x001B)


def test_process_data_watchdog_outside_op_and_without_outputs_never_trips() -> None:
    """The application acts on an expiry only in OP; SAFE-OP keeps its state. An SM2 without the watchdog
    trigger bit never starts it."""
    t = FakeTime()
    m = MiniMaster(VirtualSlave.from_drive(Drive.from_profile("hdt")), clock=t)
    m.mailbox_config()
    m.al(2)
    _pd_config(m, 28, 20)
    assert m.al(4) == (0x04, 0)
    _cycle(m, bytes(28))
    t.ms(500)
    assert m.al(4) == (0x04, 0) and m.rd(R.WD_COUNTER_PD, 1)[0] == b"\x01"
    m2 = MiniMaster(VirtualSlave.from_drive(Drive.from_profile("hdt")), clock=t)
    m2.mailbox_config()
    m2.al(2)
    m2.wr(R.SM + 16, _sm(0x1100, 28, 0x24) + _sm(0x1400, 20, 0x20))  # no watchdog trigger
    m2.wr(R.FMMU, _fmmu(0x0, 28, 0x1100, 2) + _fmmu(28, 20, 0x1400, 1))
    assert m2.al(4) == (0x04, 0)
    _cycle(m2, bytes(28))
    assert m2.al(8) == (0x08, 0)
    t.ms(500)
    assert m2.al(8) == (0x08, 0) and m2.rd(R.WD_STATUS_PD, 2)[0] == b"\x00\x00"


def test_a_slow_mailbox_holds_its_answer_back() -> None:
    """Faults.slow_mailbox: the answer waits in the slave until its time has come (the master keeps polling SM1
    and finds it empty), then comes whole; the next request is answered at once."""
    t = FakeTime()
    m = MiniMaster(VirtualSlave.from_drive(Drive.from_profile("hdt")), clock=t)
    m.mailbox_config()
    assert m.al(2) == (0x02, 0)
    m.slave.drive.faults.slow_mailbox(EcState.PREOP, 50)
    assert m.send_mbx(struct.pack("<HBHB4x", 0x2000, 0x40, 0x1018, 1)) == 1
    for _ in range(3):
        t.ms(16)
        assert m.recv_mbx() is None
    t.ms(3)
    reply = m.recv_mbx() or m.recv_mbx()  # the application fills SM1 after the frame that finds it due
    assert reply is not None and reply[6:10] == m.slave.drive.sdo_upload(0x1018, 1)
    assert m.upload(0x1018, 2) == m.slave.drive.sdo_upload(0x1018, 2)
