"""The ESC answers, the drive runs after (issue 26, item 1): the served bus answers each frame from ESC memory
alone, then runs the drive cycles whose event fired (SM2 written, a SYNC0 pulse). So the inputs a master reads in
frame k are those its drive wrote after frame k-1, as on hardware, where the drive's processor runs on its
interrupt after the ESC has forwarded the frame.

The trace test is the behaviour check of the frame path: 600 cycles of three drives (HDT and Technosoft, enabled
and moving in CSP) through the bus are compared byte for byte with the same drives driven in process through
``Drive.exchange``. Before this change the bus's inputs of cycle k equalled the in-process inputs of cycle k; now
they equal those of cycle k-1 -- exactly one cycle later, nothing else differs."""

from __future__ import annotations

import struct

import pytest

from ecattool.esi.model import Direction
from ecattool.od.model import EcState
from ecattool.sim import Drive
from ecattool.sim.bus import Bus, Cmd, Datagram, make_frame, parse_frame
from ecattool.sim.bus.loop import Loop
from ecattool.sim.esc import Clock
from ecattool.sim.esc import registers as R
from ecattool.sim.slave import VirtualSlave

PROFILES = ("hdt", "technosoft", "hdt")


def _sm(start: int, length: int, control: int) -> bytes:
    return struct.pack("<HHBBBB", start, length, control, 0, 1, 0)


def _fmmu(logical: int, length: int, physical: int, kind: int) -> bytes:
    return struct.pack("<IHBBHBBBxxx", logical, length, 0, 7, physical, 0, kind, 1)


class FakeTime:
    def __init__(self) -> None:
        self.ns = 10_000_000_000

    def __call__(self) -> int:
        return self.ns


def _prepare(drive: Drive) -> None:
    """What the master does in PRE-OP (in process for the twin, by SDO on the bus): CSP."""
    drive.sdo_download(0x6060, 0, b"\x08")


def _bus_in_op(time: FakeTime) -> tuple[Loop, list[VirtualSlave], list[tuple[int, int]]]:
    """The drives of PROFILES on one bus in OP, mapped as SOEM maps them (all outputs, then all inputs)."""
    slaves = [VirtualSlave.from_drive(Drive.from_profile(p), clock=Clock(offset_ns=i * 1_000_000_007, host=time))
              for i, p in enumerate(PROFILES)]
    loop = Loop(Bus([s.esc for s in slaves], clock=time))
    sizes = []
    for s in slaves:
        probe = Drive.from_profile(s.drive.family)
        probe.request_state(EcState.PREOP)
        probe.request_state(EcState.SAFEOP)
        sizes.append(probe.process_image_sizes())
    out_total = sum(o for o, _ in sizes)
    out_at = in_at = 0
    for i, (slave, (out_len, in_len)) in enumerate(zip(slaves, sizes)):
        st = 0x1001 + i
        assert loop.one(Datagram.make(Cmd.APWR, (-i) & 0xFFFF, R.STATION_ADDRESS, struct.pack("<H", st))).wkc == 1

        def wr(addr: int, data: bytes) -> None:
            assert loop.one(Datagram.make(Cmd.FPWR, st, addr, data)).wkc == 1  # noqa: B023

        def al(state: int) -> int:
            wr(R.AL_CONTROL, struct.pack("<H", state))
            return int.from_bytes(bytes(loop.one(Datagram.make(Cmd.FPRD, st, R.AL_STATUS, 2)).data), "little")  # noqa: B023

        mbx_out, mbx_out_len, mbx_in, mbx_in_len = slave.esc.eeprom.words(0x18, 4)
        wr(R.SM, _sm(mbx_out, mbx_out_len, 0x26) + _sm(mbx_in, mbx_in_len, 0x22))
        assert al(2) == 2
        _prepare(slave.drive)
        wr(R.SM + 16, _sm(0x1400, out_len, 0x64) + _sm(0x1600, in_len, 0x20))
        wr(R.FMMU, _fmmu(out_at, out_len, 0x1400, 2) + _fmmu(out_total + in_at, in_len, 0x1600, 1))
        out_at, in_at = out_at + out_len, in_at + in_len
        assert al(4) == 4 and al(8) == 8
    return loop, slaves, sizes


def _twin(profile: str) -> tuple[Drive, bytes]:
    """The same drive in process, brought to OP as the virtual slave brings it (one cycle on zero outputs at
    SAFE-OP and at OP: the first inputs); returns it and its inputs after that."""
    drive = Drive.from_profile(profile)
    drive.request_state(EcState.PREOP)
    _prepare(drive)
    drive.request_state(EcState.SAFEOP)
    out_len = drive.process_image_sizes()[0]
    drive.exchange(bytes(out_len))
    drive.request_state(EcState.OP)
    return drive, drive.exchange(bytes(out_len))


def _outputs(drive: Drive, out_len: int, k: int) -> bytes:
    """Cycle k's outputs: shutdown, switch on, enable, then a CSP target moving by a varying step."""
    controlword = 0x06 if k < 3 else 0x07 if k < 6 else 0x0F
    position = 0 if k < 10 else (k - 10) * (k % 7 + 1) * 3
    out = bytearray(out_len)
    for index, _sub, offset, _bits in drive.layout[Direction.RX].entries:
        if index == 0x6040:
            out[offset // 8:offset // 8 + 2] = struct.pack("<H", controlword)
        elif index == 0x607A:
            out[offset // 8:offset // 8 + 4] = struct.pack("<i", position)
    return bytes(out)


@pytest.mark.usefixtures("ideal_plant")  # its CSP target jumps by thousands of counts: a plant would fault (8611h)
def test_the_trace_of_600_cycles_is_the_in_process_one_one_cycle_later() -> None:
    time = FakeTime()
    loop, slaves, sizes = _bus_in_op(time)
    twins = [_twin(p) for p in PROFILES]
    previous = [first for _, first in twins]  # what each drive wrote into SM3 on entering OP
    in_total = sum(i for _, i in sizes)
    shifted = 0
    for k in range(600):
        time.ns += 1_000_000
        outs = [_outputs(s.drive, o, k) for s, (o, _) in zip(slaves, sizes)]
        back = loop.transact([Datagram.logical(Cmd.LRW, 0, b"".join(outs) + bytes(in_total))])
        assert back is not None and back[0].wkc == 3 * len(slaves)
        got = bytes(back[0].data[sum(o for o, _ in sizes):])
        now = [twin.exchange(out) for (twin, _), out in zip(twins, outs)]
        at = 0
        for i, (_, in_len) in enumerate(sizes):
            # the bus's inputs of cycle k are the in-process inputs of cycle k-1: the drive ran after the frame
            assert got[at:at + in_len] == previous[i], (k, i)
            shifted += previous[i] != now[i]
            at += in_len
        previous = now
    assert all(s.drive.cia402_state.name == "OPERATION_ENABLED" for s in slaves)
    assert all(s.drive.value(0x6064) == twin.value(0x6064) != 0 for s, (twin, _) in zip(slaves, twins))
    assert shifted > 500  # the inputs move from cycle to cycle: the shift is visible, the check is not vacuous


def test_the_frame_is_answered_before_the_drive_runs() -> None:
    """``Bus.process`` answers from the ESC; the drive's cycle comes in ``run_applications`` (the transports
    call it once the reply is out), or at the latest before the next frame."""
    time = FakeTime()
    loop, slaves, sizes = _bus_in_op(time)
    bus = loop.bus
    drive = slaves[0].drive
    out_len = sizes[0][0]
    frame = make_frame([Datagram.logical(Cmd.LRW, 0, _outputs(drive, out_len, 0).ljust(
        sum(o + i for o, i in sizes), b"\x00"))])
    assert drive.value(0x6040) == 0
    assert bus.process(frame) is not None
    assert drive.value(0x6040) == 0 and bus.pending  # answered; the drive has not seen the outputs yet
    bus.run_applications()
    assert drive.value(0x6040) == 0x06 and not bus.pending
    frame7 = make_frame([Datagram.logical(Cmd.LRW, 0, _outputs(drive, out_len, 3).ljust(
        sum(o + i for o, i in sizes), b"\x00"))])
    bus.process(frame7)
    reply = bus.process(make_frame([Datagram.make(Cmd.BRD, 0, R.AL_STATUS, 2)]))  # runs the pending cycle first
    assert drive.value(0x6040) == 0x07 and reply is not None
    parsed = parse_frame(reply)
    assert parsed is not None and parsed.datagrams[0].wkc == len(slaves)


def _counting(slave: VirtualSlave) -> list[bytes]:
    """The drive cycles ``slave`` runs from now on (each the outputs it ran on)."""
    cycles: list[bytes] = []
    original = slave.drive.exchange

    def counting(outputs: bytes) -> bytes:
        cycles.append(bytes(outputs))
        return original(outputs)

    slave.drive.exchange = counting  # type: ignore[method-assign]
    return cycles


def test_with_sync0_on_the_drive_runs_on_each_pulse_even_without_new_outputs() -> None:
    """DC synchronous: a SYNC0 pulse is the drive's event too. A frame that does not write SM2 (a mailbox poll)
    after a pulse lets the drive run its cycle on the last outputs; within one SYNC0 cycle it runs once."""
    time = FakeTime()
    loop, slaves, sizes = _bus_in_op(time)
    slave = slaves[0]
    st = 0x1001
    now = int.from_bytes(bytes(loop.one(Datagram.make(Cmd.FPRD, st, R.DC_SYSTEM_TIME, 8)).data), "little")
    loop.one(Datagram.make(Cmd.FPWR, st, R.DC_SYNC0_CYCLE, struct.pack("<I", 1_000_000)))
    loop.one(Datagram.make(Cmd.FPWR, st, R.DC_START_TIME, struct.pack("<Q", now + 500_000)))
    loop.one(Datagram.make(Cmd.FPWR, st, R.DC_ACTIVATION, b"\x03"))
    total = sum(o + i for o, i in sizes)
    cycles = _counting(slave)
    poll = Datagram.make(Cmd.FPRD, st, R.AL_STATUS, 2)
    loop.one(Datagram.logical(Cmd.LRW, 0, bytes(total)))  # SM2 written: one cycle
    assert len(cycles) == 1
    time.ns += 1_000_000  # the first pulse has come
    loop.one(poll)
    time.ns += 1_000_000  # the next one
    loop.one(poll)
    assert len(cycles) == 2  # on a pulse after the first one seen, without new outputs
    loop.one(poll)
    assert len(cycles) == 2  # no new pulse: nothing to do
    time.ns += 3_000_000
    loop.one(poll)
    assert len(cycles) == 3  # once per frame, however many pulses passed
    assert all(len(n) == sizes[0][0] for n in cycles)


def test_on_its_own_clock_the_drive_runs_the_cycles_its_time_holds() -> None:
    """``sim serve`` runs each drive on its own clock: without SYNC0 the drive runs as many cycles of its cycle
    time (60C2h: HDT 2 ms, Technosoft 1 ms) as ended since its last one, whatever the master's frames do -- a late
    master does not slow the drive's motion down, frames faster than its cycle do not speed it up; an event
    before the next cycle waits for it; a long silence is made up to MAX_CATCH_UP cycles. Paced by frames (the
    default) the same frames give one cycle each."""
    from ecattool.sim.slave import MAX_CATCH_UP

    gaps_us = [1000, 3000, 500, 500, 400, 5000, 250_000, 1000, 999, 2]
    own = {"technosoft": [1, 3, 0, 1, 0, 5, MAX_CATCH_UP, 1, 0, 1],  # after a first frame that runs one cycle
           "hdt": [0, 2, 0, 0, 0, 3, MAX_CATCH_UP, 0, 0, 1]}
    for own_clock in (True, False):
        time = FakeTime()
        loop, slaves, sizes = _bus_in_op(time)
        for s in slaves:
            s.own_clock = own_clock
        cycles = [_counting(s) for s in slaves]
        frame = [Datagram.logical(Cmd.LRW, 0, bytes(sum(o + i for o, i in sizes)))]
        loop.transact(frame)
        assert [len(c) for c in cycles] == [1] * len(slaves)
        ran: list[list[int]] = [[] for _ in slaves]
        for gap in gaps_us:
            time.ns += gap * 1000
            before = [len(c) for c in cycles]
            loop.transact(frame)
            for r, c, b in zip(ran, cycles, before):
                r.append(len(c) - b)
        for profile, r in zip(PROFILES, ran):
            assert r == (own[profile] if own_clock else [1] * len(gaps_us)), (own_clock, profile)
    assert MAX_CATCH_UP < 125


def test_on_its_own_clock_with_sync0_each_pulse_is_a_cycle() -> None:
    """DC synchronous on its own clock: the drive runs one cycle per SYNC0 pulse that came since its last one
    (several after a late frame), and outputs written between two pulses wait for the next pulse."""
    time = FakeTime()
    loop, slaves, sizes = _bus_in_op(time)
    slave = slaves[0]
    slave.own_clock = True
    st = 0x1001
    now = int.from_bytes(bytes(loop.one(Datagram.make(Cmd.FPRD, st, R.DC_SYSTEM_TIME, 8)).data), "little")
    loop.one(Datagram.make(Cmd.FPWR, st, R.DC_SYNC0_CYCLE, struct.pack("<I", 1_000_000)))
    loop.one(Datagram.make(Cmd.FPWR, st, R.DC_START_TIME, struct.pack("<Q", now + 500_000)))
    loop.one(Datagram.make(Cmd.FPWR, st, R.DC_ACTIVATION, b"\x03"))
    cycles = _counting(slave)
    total = sum(o + i for o, i in sizes)
    lrw = [Datagram.logical(Cmd.LRW, 0, bytes(total))]
    loop.transact(lrw)
    assert len(cycles) == 0  # outputs before the first pulse: they wait for it
    time.ns += 1_000_000  # the first pulse has come
    loop.transact(lrw)
    assert len(cycles) == 1
    time.ns += 300_000
    loop.transact(lrw)
    assert len(cycles) == 1  # no new pulse: the new outputs wait
    time.ns += 700_000  # the next pulse
    loop.transact(lrw)
    assert len(cycles) == 2
    time.ns += 4_000_000  # four pulses, and new outputs: the pulses before they came ran on the old ones
    new = bytearray(total)
    new[0] = 0x06  # the first drive's first output byte changes
    loop.transact([Datagram.logical(Cmd.LRW, 0, bytes(new))])
    assert len(cycles) == 6
    old = bytes(sizes[0][0])
    assert cycles[2:5] == [old] * 3 and cycles[5] == bytes(new[:sizes[0][0]])
