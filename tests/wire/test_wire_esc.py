"""The ESC model and the datagram engine through the in-process transport (issue 13, items 1 and 2)."""

from __future__ import annotations

import struct

import pytest

from ecattool import profiles
from ecattool.sii.builder import build
from ecattool.sim.bus import Bus, Cmd, Datagram, FrameError, make_frame, parse_frame
from ecattool.sim.bus.frame import decode_datagrams, encode_datagrams
from ecattool.sim.bus.loop import Loop
from ecattool.sim.esc import Clock, Esc
from ecattool.sim.esc import registers as R


def _image(profile: str = "hdt") -> bytes:
    return build(profiles.load(profile)).to_bytes()


def _loop(n: int = 3, profile: str = "hdt", **kw: object) -> Loop:
    image = _image(profile)
    return Loop(Bus([Esc(image, clock=Clock(offset_ns=i * 1_000_000_007), **kw) for i in range(n)]))  # type: ignore[arg-type]


def _pos(i: int) -> int:
    """The ADP that addresses slave ``i`` by position."""
    return (-i) & 0xFFFF


def _configure_addresses(loop: Loop) -> None:
    for i in range(len(loop.bus.escs)):
        assert loop.one(Datagram.make(Cmd.APWR, _pos(i), R.STATION_ADDRESS, struct.pack("<H", 0x1001 + i))).wkc == 1


# --- frame codec ----------------------------------------------------------------------------------
def test_codec_round_trip_several_datagrams() -> None:
    dgs = [Datagram.make(Cmd.BRD, 0, 0x0000, 2, index=1), Datagram.logical(Cmd.LRW, 0x10000, b"\x01\x02\x03", 2)]
    dgs[1].wkc, dgs[1].irq, dgs[1].circulated = 7, 0x55, True
    back = decode_datagrams(encode_datagrams(dgs))
    assert back == dgs
    raw = make_frame(dgs)
    assert len(raw) == 60  # padded to the Ethernet minimum
    frame = parse_frame(raw)
    assert frame is not None and frame.datagrams == dgs and frame.dst == b"\xff" * 6


def test_codec_ignores_other_frames_and_rejects_bad_lengths() -> None:
    arp = b"\xff" * 6 + b"\x02" * 6 + b"\x08\x06" + bytes(46)
    assert parse_frame(arp) is None
    raw = bytearray(make_frame([Datagram.make(Cmd.BRD, 0, 0, 4)]))
    raw[14] = 0xFF  # header length 0x0FF: past the end
    raw[15] = (raw[15] & 0xF8) | 0x07
    with pytest.raises(FrameError):
        parse_frame(bytes(raw))
    loop = _loop(1)
    loop.send(arp)
    assert loop.recv() is None  # not EtherCAT: ignored, no reply
    loop.send(bytes(raw))
    assert loop.recv() is None and loop.bus.escs[0].mem[R.RX_ERROR_COUNTER] == 1


# --- addressing and working counters ------------------------------------------------------------
def test_broadcast_read_counts_slaves_and_ors_data() -> None:
    loop = _loop(3)
    d = loop.one(Datagram.make(Cmd.BRD, 0, R.TYPE, 2))
    assert d.wkc == 3 and d.data[0] == 0x11 and d.adp == 3  # every slave increments ADP
    loop.bus.escs[1].mem[R.AL_STATUS_CODE] = 0x1E
    d = loop.one(Datagram.make(Cmd.BRD, 0, R.AL_STATUS_CODE, 2))
    assert d.data[0] == 0x1E  # OR of all slaves


def test_auto_increment_and_node_addressing() -> None:
    loop = _loop(3)
    _configure_addresses(loop)
    assert [e.station_address for e in loop.bus.escs] == [0x1001, 0x1002, 0x1003]
    d = loop.one(Datagram.make(Cmd.APRD, _pos(2), R.STATION_ADDRESS, 2))
    assert d.wkc == 1 and d.data == struct.pack("<H", 0x1003) and d.adp == 1  # -2 + 3 slaves
    assert loop.one(Datagram.make(Cmd.APRD, _pos(3), R.STATION_ADDRESS, 2)).wkc == 0  # no fourth slave
    d = loop.one(Datagram.make(Cmd.FPRD, 0x1002, R.STATION_ADDRESS, 2))
    assert d.wkc == 1 and d.data == struct.pack("<H", 0x1002)
    assert loop.one(Datagram.make(Cmd.FPRD, 0x2000, R.STATION_ADDRESS, 2)).wkc == 0


def test_read_write_commands_count_three() -> None:
    loop = _loop(2)
    _configure_addresses(loop)
    d = loop.one(Datagram.make(Cmd.FPRW, 0x1002, R.ECAT_EVENT_MASK, struct.pack("<H", 0x0004)))
    assert d.wkc == 3 and d.data == b"\x00\x00"  # the old value comes back, the new one is stored
    assert loop.bus.escs[1].u16(R.ECAT_EVENT_MASK) == 0x0004
    d = loop.one(Datagram.make(Cmd.APRW, _pos(0), R.ECAT_EVENT_MASK, struct.pack("<H", 0x0008)))
    assert d.wkc == 3
    d = loop.one(Datagram.make(Cmd.BRW, 0, R.ECAT_EVENT_MASK, b"\x00\x00"))
    assert d.wkc == 6 and d.data == struct.pack("<H", 0x000C)  # OR of 0x0008 and 0x0004
    # a write to a read-only register is taken (working counter) but changes nothing
    d = loop.one(Datagram.make(Cmd.FPWR, 0x1001, R.TYPE, b"\x99"))
    assert d.wkc == 1 and loop.bus.escs[0].mem[R.TYPE] == 0x11


def test_armw_frmw_distribute_the_reference_clock() -> None:
    loop = _loop(3)
    _configure_addresses(loop)
    ref = loop.one(Datagram.make(Cmd.FPRD, 0x1001, R.DC_SYSTEM_TIME, 8))
    d = loop.one(Datagram.make(Cmd.FRMW, 0x1001, R.DC_SYSTEM_TIME, 8))
    assert d.wkc == 3  # the reference reads (+1), the two others write (+1 each)
    assert int.from_bytes(d.data, "little") >= int.from_bytes(ref.data, "little")
    # the others compared it with their own system time: slave 1 runs 1.000000007 s ahead of slave 0
    diff = loop.bus.escs[1].u32(R.DC_SYSTEM_DIFFERENCE)
    assert diff & 0x80000000 and 999_000_000 < diff & 0x7FFFFFFF < 1_001_000_000
    d = loop.one(Datagram.make(Cmd.ARMW, _pos(1), R.DC_SYSTEM_TIME, 8))
    assert d.wkc == 3


def test_dc_receive_time_latch_orders_ports() -> None:
    loop = _loop(3)
    _configure_addresses(loop)
    assert loop.one(Datagram.make(Cmd.BWR, 0, R.DC_RECEIVE_TIME, 4)).wkc == 3
    for i, esc in enumerate(loop.bus.escs):
        p0, p1 = esc.u32(R.DC_RECEIVE_TIME), esc.u32(R.DC_RECEIVE_TIME + 4)
        if i < 2:
            assert (p1 - p0) & 0xFFFFFFFF == 2 * (2 - i) * loop.bus.hop_ns  # round trip through the rest
        assert esc.u64(R.DC_RECEIVE_TIME_PU) & 0xFFFFFFFF == p0
    dl = [loop.one(Datagram.make(Cmd.FPRD, 0x1001 + i, R.DL_STATUS, 2)).data for i in range(3)]
    assert [int.from_bytes(x, "little") & 0x0F00 for x in dl] == [0x0A00, 0x0A00, 0x0600]  # last: port 1 closed


def test_closed_port_stops_the_frame() -> None:
    loop = _loop(3)
    # DL control 0x0101: port 1 loop always closed (bits 2..3 = 11) on the first slave
    assert loop.one(Datagram.make(Cmd.APWR, 0, R.DL_CONTROL + 1, b"\x0C")).wkc == 1
    assert loop.one(Datagram.make(Cmd.BRD, 0, R.TYPE, 1)).wkc == 1


def test_several_datagrams_in_one_frame() -> None:
    loop = _loop(2)
    back = loop.transact([Datagram.make(Cmd.APWR, _pos(1), R.STATION_ADDRESS, b"\x05\x00", index=1),
                          Datagram.make(Cmd.FPRD, 5, R.STATION_ADDRESS, 2, index=2),
                          Datagram.make(Cmd.BRD, 0, R.TYPE, 1, index=3)])
    assert back is not None
    assert [(d.index, d.wkc) for d in back] == [(1, 1), (2, 1), (3, 2)]
    assert back[1].data == b"\x05\x00"


def test_al_control_in_device_emulation() -> None:
    loop = _loop(2)
    assert loop.one(Datagram.make(Cmd.BWR, 0, R.AL_CONTROL, b"\x02\x00")).wkc == 2
    d = loop.one(Datagram.make(Cmd.BRD, 0, R.AL_STATUS, 2))
    assert d.data == b"\x02\x00" and d.wkc == 2


# --- SII EEPROM interface --------------------------------------------------------------------------
def _eeprom_read(loop: Loop, station: int, word: int) -> bytes:
    """What SOEM does: control word + address in one write, poll busy, read the data registers."""
    assert loop.one(Datagram.make(Cmd.FPWR, station, R.EEPROM_CONTROL,
                                  struct.pack("<HI", R.EE_CMD_READ, word))).wkc == 1
    polls = 0
    while True:
        status = int.from_bytes(loop.one(Datagram.make(Cmd.FPRD, station, R.EEPROM_CONTROL, 2)).data, "little")
        polls += 1
        if not status & R.EE_BUSY:
            break
        assert polls < 5
    assert not status & (R.EE_ACK_ERROR | R.EE_WRITE_ERROR)
    n = 8 if status & R.EE_READ_8 else 4
    return bytes(loop.one(Datagram.make(Cmd.FPRD, station, R.EEPROM_DATA, n)).data)


@pytest.mark.parametrize("read_8", [True, False])
def test_eeprom_reads_the_sii_that_sii_build_makes(read_8: bool) -> None:
    image = _image("technosoft-ipos")
    loop = Loop(Bus([Esc(image, read_8=read_8)]))
    _configure_addresses(loop)
    got = bytearray()
    step = 4 if read_8 else 2
    for word in range(0, len(image) // 2, step):
        got += _eeprom_read(loop, 0x1001, word)
    assert bytes(got[:len(image)]) == image
    assert loop.bus.escs[0].alias == int.from_bytes(image[8:10], "little")


def test_eeprom_write_needs_enable_and_reload_checks_crc() -> None:
    image = _image("controltechniques")
    loop = Loop(Bus([Esc(image)]))
    _configure_addresses(loop)
    esc = loop.bus.escs[0]
    # write word 4 (alias) without the write enable bit: error, nothing written
    loop.one(Datagram.make(Cmd.FPWR, 0x1001, R.EEPROM_DATA, b"\x07\x00"))
    loop.one(Datagram.make(Cmd.FPWR, 0x1001, R.EEPROM_CONTROL, struct.pack("<HI", R.EE_CMD_WRITE, 4)))
    status = int.from_bytes(loop.one(Datagram.make(Cmd.FPRD, 0x1001, R.EEPROM_CONTROL, 2)).data, "little")
    assert status & R.EE_WRITE_ERROR and esc.eeprom.words(4, 1) == [int.from_bytes(image[8:10], "little")]
    loop.one(Datagram.make(Cmd.FPWR, 0x1001, R.EEPROM_CONTROL,
                           struct.pack("<HI", R.EE_CMD_WRITE | R.EE_WRITE_ENABLE, 4)))
    status = int.from_bytes(loop.one(Datagram.make(Cmd.FPRD, 0x1001, R.EEPROM_CONTROL, 2)).data, "little")
    assert status & R.EE_BUSY  # busy for one status read, then done
    status = int.from_bytes(loop.one(Datagram.make(Cmd.FPRD, 0x1001, R.EEPROM_CONTROL, 2)).data, "little")
    assert not status & (R.EE_BUSY | R.EE_WRITE_ERROR | R.EE_WRITE_ENABLE)
    assert _eeprom_read(loop, 0x1001, 4)[:2] == b"\x07\x00"
    # the CRC of words 0..6 no longer matches word 7: a reload reports the checksum error, the alias stays
    loop.one(Datagram.make(Cmd.FPWR, 0x1001, R.EEPROM_CONTROL, struct.pack("<HI", R.EE_CMD_RELOAD, 0)))
    loop.one(Datagram.make(Cmd.FPRD, 0x1001, R.EEPROM_CONTROL, 2))
    status = int.from_bytes(loop.one(Datagram.make(Cmd.FPRD, 0x1001, R.EEPROM_CONTROL, 2)).data, "little")
    assert status & R.EE_CHECKSUM_ERROR and esc.alias == int.from_bytes(image[8:10], "little")
    # an address past the end: acknowledge error
    loop.one(Datagram.make(Cmd.FPWR, 0x1001, R.EEPROM_CONTROL, struct.pack("<HI", R.EE_CMD_READ, 0x10000)))
    loop.one(Datagram.make(Cmd.FPRD, 0x1001, R.EEPROM_CONTROL, 2))
    status = int.from_bytes(loop.one(Datagram.make(Cmd.FPRD, 0x1001, R.EEPROM_CONTROL, 2)).data, "little")
    assert status & R.EE_ACK_ERROR


# --- FMMUs and logical addressing ----------------------------------------------------------------
def _fmmu(logical: int, length: int, start_bit: int, stop_bit: int, physical: int, phys_bit: int,
          kind: int) -> bytes:
    return struct.pack("<IHBBHBBBxxx", logical, length, start_bit, stop_bit, physical, phys_bit, kind, 1)


def test_lrw_bit_granular_fmmus_and_working_counter() -> None:
    loop = _loop(2)
    _configure_addresses(loop)
    a, b = loop.bus.escs
    # slave 0: outputs = logical bits 0..3 of byte 0x100 -> physical 0x1100 bits 0..3; inputs = byte 0x101
    loop.one(Datagram.make(Cmd.FPWR, 0x1001, R.FMMU, _fmmu(0x100, 1, 0, 3, 0x1100, 0, 2)
                           + _fmmu(0x101, 1, 0, 7, 0x1200, 0, 1)))
    # slave 1: outputs = bits 4..7 of the same byte -> physical 0x1100 bits 2..5; inputs: bits 4..7 of 0x102
    loop.one(Datagram.make(Cmd.FPWR, 0x1002, R.FMMU, _fmmu(0x100, 1, 4, 7, 0x1100, 2, 2)
                           + _fmmu(0x102, 1, 4, 7, 0x1200, 0, 1)))
    a.mem[0x1200], b.mem[0x1200] = 0xA5, 0x0C
    d = loop.one(Datagram.logical(Cmd.LRW, 0x100, b"\x9E\x00\x03"))
    assert d.wkc == 6  # each slave: read +1, write +2
    assert a.mem[0x1100] == 0x0E and b.mem[0x1100] == (0x9 << 2)
    assert d.data == bytes([0x9E, 0xA5, 0xC3])  # slave 1's 4 input bits land in bits 4..7, bits 0..3 kept
    d = loop.one(Datagram.logical(Cmd.LRD, 0x101, 1))
    assert d.wkc == 1 and d.data == b"\xA5"
    d = loop.one(Datagram.logical(Cmd.LWR, 0x100, b"\x01"))
    assert d.wkc == 2 and a.mem[0x1100] == 0x01
    assert loop.one(Datagram.logical(Cmd.LRD, 0x200, 4)).wkc == 0  # nothing mapped there


def test_mailbox_sync_managers_refuse_when_full_or_empty() -> None:
    loop = _loop(1)
    _configure_addresses(loop)
    esc = loop.bus.escs[0]
    sm0 = struct.pack("<HHBBBB", 0x1000, 128, 0x26, 0, 1, 0)
    sm1 = struct.pack("<HHBBBB", 0x1080, 128, 0x22, 0, 1, 0)
    assert loop.one(Datagram.make(Cmd.FPWR, 0x1001, R.SM, sm0 + sm1)).wkc == 1
    assert loop.one(Datagram.make(Cmd.FPRD, 0x1001, 0x1080, 128)).wkc == 0  # SM1 empty: no working counter
    assert loop.one(Datagram.make(Cmd.FPWR, 0x1001, 0x1000, bytes(range(128)))).wkc == 1
    status = loop.one(Datagram.make(Cmd.FPRD, 0x1001, R.SM + 5, 1)).data[0]
    assert status & 0x08  # SM0 full: the application (none here) has not read it
    assert loop.one(Datagram.make(Cmd.FPWR, 0x1001, 0x1000, bytes(128))).wkc == 0  # full: refused
    esc.pdi_mailbox_take(0)
    assert esc.pdi_mailbox_put(1, b"reply")
    d = loop.one(Datagram.make(Cmd.FPRD, 0x1001, 0x1080, 128))
    assert d.wkc == 1 and d.data[:5] == b"reply"
    assert loop.one(Datagram.make(Cmd.FPRD, 0x1001, 0x1080, 128)).wkc == 0  # read to the end: empty again


def test_sync0_next_pulse_and_activation_status() -> None:
    loop = _loop(1)
    _configure_addresses(loop)
    now = int.from_bytes(loop.one(Datagram.make(Cmd.FPRD, 0x1001, R.DC_SYSTEM_TIME, 8)).data, "little")
    start = now - 3_500_000  # already past: the next pulse is the first cycle boundary after the system time
    loop.one(Datagram.make(Cmd.FPWR, 0x1001, R.DC_SYNC0_CYCLE, struct.pack("<I", 1_000_000)))
    loop.one(Datagram.make(Cmd.FPWR, 0x1001, R.DC_START_TIME, struct.pack("<Q", start)))
    assert loop.one(Datagram.make(Cmd.FPRD, 0x1001, R.DC_ACTIVATION_STATUS, 1)).data == b"\x00"
    loop.one(Datagram.make(Cmd.FPWR, 0x1001, R.DC_ACTIVATION, b"\x03"))
    back = loop.one(Datagram.make(Cmd.FPRD, 0x1001, R.DC_ACTIVATION_STATUS, 0x14))
    # the first pulse is no longer pending (0x0984 bit 0), SYNC0 has pulsed (0x098E)
    assert back.data[0] == 0x00 and back.data[R.DC_SYNC0_STATUS - R.DC_ACTIVATION_STATUS] == 0x01
    nxt = int.from_bytes(back.data[R.DC_START_TIME - R.DC_ACTIVATION_STATUS:][:8], "little")
    assert (nxt - start) % 1_000_000 == 0 and nxt > now


def _dc_registers(loop: Loop) -> tuple[int, int, int, int, int, int]:
    """(system time, 0x0984, 0x098E, 0x098F, next SYNC0 0x0990, next SYNC1 0x0998) in one frame."""
    d = loop.transact([Datagram.make(Cmd.FPRD, 0x1001, R.DC_SYSTEM_TIME, 8),
                       Datagram.make(Cmd.FPRD, 0x1001, R.DC_ACTIVATION_STATUS, 0x1C)])
    assert d is not None
    regs = bytes(d[1].data)
    at = R.DC_ACTIVATION_STATUS
    return (int.from_bytes(d[0].data, "little"), regs[0], regs[R.DC_SYNC0_STATUS - at], regs[R.DC_SYNC1_STATUS - at],
            int.from_bytes(regs[R.DC_START_TIME - at:][:8], "little"),
            int.from_bytes(regs[R.DC_NEXT_SYNC1 - at:][:8], "little"))


@pytest.mark.parametrize(("sync1_cycle", "period"), [
    (0, 1_000_000),              # SYNC1 reflects SYNC0
    (250_000, 1_000_000),        # below the SYNC0 cycle: every SYNC0 pulse, 250 us later
    (1_000_000, 1_000_000),      # equal: with the next SYNC0 pulse
    (1_500_000, 2_000_000),      # between 1x and 2x: every second SYNC0 pulse, 1.5 ms after it
    (3_000_000, 3_000_000),      # 3x: every third
])
def test_sync1_follows_sync0(sync1_cycle: int, period: int) -> None:
    """Beckhoff ESC technology, SYNC1 generation: each SYNC1 pulse comes the SYNC1 cycle after a SYNC0 pulse, the
    next one after the first SYNC0 pulse at or after it (0: SYNC1 is SYNC0). 0x0998 reads the next SYNC1 pulse;
    0x0984 bit 0/1 say the first SYNC0/SYNC1 pulse is still pending. SOEM's dc_sync with SYNC1 writes 0x07."""
    cycle = 1_000_000
    loop = _loop(1)
    _configure_addresses(loop)
    now = int.from_bytes(loop.one(Datagram.make(Cmd.FPRD, 0x1001, R.DC_SYSTEM_TIME, 8)).data, "little")
    start = now + 5_000_000_000  # 5 s ahead: nothing pulses during the first reads
    loop.one(Datagram.make(Cmd.FPWR, 0x1001, R.DC_SYNC0_CYCLE, struct.pack("<II", cycle, sync1_cycle)))
    loop.one(Datagram.make(Cmd.FPWR, 0x1001, R.DC_START_TIME, struct.pack("<Q", start)))
    loop.one(Datagram.make(Cmd.FPWR, 0x1001, R.DC_ACTIVATION, b"\x07"))
    _, pending, s0, s1, next0, next1 = _dc_registers(loop)
    first1 = start + sync1_cycle
    assert (pending, s0, s1, next0, next1) == (0x03, 0, 0, start, first1)
    esc = loop.bus.escs[0]
    esc.clock.offset_ns += 7_000_000_000  # 7 s later in the slave's time: 2 s of pulses have passed
    t, pending, s0, s1, next0, next1 = _dc_registers(loop)
    assert (pending, s0, s1) == (0x00, 0x01, 0x01)
    assert next0 >= t and (next0 - start) % cycle == 0 and next0 - t <= cycle
    assert next1 >= t and (next1 - first1) % period == 0 and next1 - t <= period
    # the master rewrites 0x0990 while the unit runs: the unit keeps the start time it took
    loop.one(Datagram.make(Cmd.FPWR, 0x1001, R.DC_START_TIME, struct.pack("<Q", start + 123)))
    assert (_dc_registers(loop)[4] - start) % cycle == 0


def test_loop_faults_lose_or_spoil_frames() -> None:
    """The in-process transport's fault hooks: a lost frame never reaches the slaves; a frame with a bad
    checksum is counted by every slave it passes (invalid frame counter 0x0300) and not answered."""
    loop = _loop(2)
    loop.faults.append(lambda raw: (None, True))
    assert loop.transact([Datagram.make(Cmd.BWR, 0, R.ECAT_EVENT_MASK, b"\x04\x00")]) is None
    assert [e.u16(R.ECAT_EVENT_MASK) for e in loop.bus.escs] == [0, 0]  # lost on the way: nothing written
    loop.faults.append(lambda raw: (raw, False))
    assert loop.transact([Datagram.make(Cmd.BWR, 0, R.ECAT_EVENT_MASK, b"\x04\x00")]) is None
    assert [e.mem[R.RX_ERROR_COUNTER] for e in loop.bus.escs] == [1, 1]
    assert [e.u16(R.ECAT_EVENT_MASK) for e in loop.bus.escs] == [0, 0]
    d = loop.one(Datagram.make(Cmd.BWR, 0, R.RX_ERROR_COUNTER, b"\x00"))  # writing a counter clears it
    assert d.wkc == 2 and [e.mem[R.RX_ERROR_COUNTER] for e in loop.bus.escs] == [0, 0]
