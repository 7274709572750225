"""What the frame path keeps between frames is forgotten when what it was derived from changes (issue 13,
item 7): the ESC's pieces of an access at sync manager boundaries and its FMMU geometry per logical address
(``ecattool.sim.esc.mapping``), and the drive's byte slots of its process image (``Layout.slots``). Each test
uses a configuration for a cycle, changes it, and checks the next cycle follows the new one. The shortcuts the
cycle takes (whole bytes instead of bits, integers instead of fractions) agree with the general way."""

from __future__ import annotations

import gc
import struct
from fractions import Fraction

import pytest
from hypothesis import given
from hypothesis import strategies as st

from ecattool import profiles
from ecattool.od.model import EcState
from ecattool.sii.builder import build
from ecattool.sim import Drive
from ecattool.sim.bus import Bus, Cmd, Datagram
from ecattool.sim.bus.loop import Loop
from ecattool.sim.drive.core import GAP, TX, Layout
from ecattool.sim.esc import Esc, EscApplication
from ecattool.sim.esc import registers as R
from ecattool.sim.esc.mapping import Derived
from ecattool.sim.units import Units, floor_div, to_int

ST = 0x1001


class _Recorder(EscApplication):
    def __init__(self) -> None:
        self.written: list[tuple[int, bytes]] = []

    def buffer_written(self, esc: Esc, sm: int, data: bytes) -> None:
        self.written.append((sm, data))


def _sm(start: int, length: int, control: int, enable: int = 1) -> bytes:
    return struct.pack("<HHBBBB", start, length, control, 0, enable, 0)


def _fmmu(logical: int, length: int, start_bit: int, stop_bit: int, physical: int, kind: int) -> bytes:
    return struct.pack("<IHBBHBBBxxx", logical, length, start_bit, stop_bit, physical, 0, kind, 1)


def _one_slave() -> tuple[Loop, Esc, _Recorder]:
    app = _Recorder()
    esc = Esc(build(profiles.load("hdt")).to_bytes(), app=app)
    loop = Loop(Bus([esc]))
    assert loop.one(Datagram.make(Cmd.APWR, 0, R.STATION_ADDRESS, struct.pack("<H", ST))).wkc == 1
    return loop, esc, app


def _wr(loop: Loop, addr: int, data: bytes) -> int:
    return loop.one(Datagram.make(Cmd.FPWR, ST, addr, data)).wkc


def test_a_sync_manager_moved_after_a_cycle_is_honoured() -> None:
    loop, esc, app = _one_slave()
    _wr(loop, R.SM + 16, _sm(0x1100, 4, 0x64))  # SM2: buffered, ECAT writes
    assert _wr(loop, 0x1100, b"\x01\x02\x03\x04") == 1
    assert app.written == [(2, b"\x01\x02\x03\x04")]
    _wr(loop, R.SM + 16, _sm(0x1200, 4, 0x64))  # the same access now misses the SM: plain RAM
    assert _wr(loop, 0x1100, b"\x05\x06\x07\x08") == 1
    assert app.written == [(2, b"\x01\x02\x03\x04")] and esc.mem[0x1100:0x1104] == b"\x05\x06\x07\x08"
    assert _wr(loop, 0x1200, b"\x09\x0A\x0B\x0C") == 1
    assert app.written[-1] == (2, b"\x09\x0A\x0B\x0C")
    _wr(loop, R.SM + 16, _sm(0x1200, 4, 0x64, enable=0))  # disabled: plain RAM again
    assert _wr(loop, 0x1200, b"\x00\x00\x00\x00") == 1 and len(app.written) == 2
    _wr(loop, R.SM + 16, _sm(0x1200, 4, 0x20))  # enabled for ECAT reads: the master's write is refused
    assert _wr(loop, 0x1200, b"\xFF\xFF\xFF\xFF") == 0


def test_an_fmmu_reconfigured_after_a_cycle_is_honoured() -> None:
    loop, esc, _ = _one_slave()
    _wr(loop, R.FMMU, _fmmu(0x100, 2, 0, 7, 0x1100, 2))
    assert loop.one(Datagram.logical(Cmd.LWR, 0x100, b"\xAA\xBB")).wkc == 1
    assert esc.mem[0x1100:0x1102] == b"\xAA\xBB"
    # another physical address, then another logical window with bit granularity, for the same datagram
    _wr(loop, R.FMMU, _fmmu(0x100, 2, 0, 7, 0x1180, 2))
    assert loop.one(Datagram.logical(Cmd.LWR, 0x100, b"\x11\x22")).wkc == 1
    assert esc.mem[0x1180:0x1182] == b"\x11\x22" and esc.mem[0x1100:0x1102] == b"\xAA\xBB"
    esc.mem[0x1180] = 0
    _wr(loop, R.FMMU, _fmmu(0x100, 1, 4, 7, 0x1180, 2))  # logical bits 4..7 of 0x100 -> physical bits 0..3
    assert loop.one(Datagram.logical(Cmd.LWR, 0x100, b"\x5F\x22")).wkc == 1
    assert esc.mem[0x1180] == 0x05
    # from writing to reading: the datagram now takes the physical byte
    _wr(loop, R.FMMU, _fmmu(0x100, 1, 0, 7, 0x1180, 1))
    d = loop.one(Datagram.logical(Cmd.LRW, 0x100, b"\x00\x77"))
    assert d.wkc == 1 and d.data == bytearray(b"\x05\x77")
    _wr(loop, R.FMMU, bytes(16))  # disabled: nothing mapped
    assert loop.one(Datagram.logical(Cmd.LRW, 0x100, 2)).wkc == 0


def test_derived_values_follow_their_source_and_stay_bounded() -> None:
    memo: Derived[int, str] = Derived(limit=2)
    calls: list[int] = []

    def compute(k: int) -> str:
        calls.append(k)
        return f"v{k}"

    a, b = object(), object()
    assert memo.get(a, 1, lambda: compute(1)) == "v1" and memo.get(a, 1, lambda: compute(1)) == "v1"
    assert calls == [1]
    assert memo.get(b, 1, lambda: compute(1)) == "v1" and calls == [1, 1]  # another source: computed again
    memo.get(b, 2, lambda: compute(2))
    memo.get(b, 3, lambda: compute(3))  # past the limit: starts over
    memo.get(b, 1, lambda: compute(1))
    assert calls == [1, 1, 2, 3, 1]


def test_layout_slots_and_pieces_follow_the_entries() -> None:
    layout = Layout(32, [(0x6040, 0, 0, 16), (0, 0, 16, 4), (0x6060, 0, 20, 4), (0x607A, 0, 24, 8)])
    assert layout.slots() == (((0x6040, 0), 0, 2, 0, 16), ((0x6060, 0), -1, -1, 20, 4), ((0x607A, 0), 3, 4, 24, 8))
    assert layout.pieces() is None  # bits 16..23 are not whole bytes: the exchange takes the bit path
    layout.entries[1:3] = [(0, 0, 16, 8)]
    assert layout.slots() == (((0x6040, 0), 0, 2, 0, 16), ((0x607A, 0), 3, 4, 24, 8))
    assert layout.pieces() == ((((0x6040, 0), bytes(2)), (GAP, bytes(1)), ((0x607A, 0), bytes(1))), (2, 1, 1))
    assert Layout().pieces() == ((), ()) and Layout().slots() == ()  # no process data: an empty image
    layout.entries[0] = (0x6041, 0, 0, 16)
    assert layout.slots()[0] == ((0x6041, 0), 0, 2, 0, 16)


def test_inputs_on_whole_bytes_and_bits_agree() -> None:
    """The same objects packed through whole-byte pieces and through the bit path (a 4-bit gap) give the same
    bytes where they overlap; a value longer than its mapping is cut, a shorter one padded."""
    drive = Drive.from_profile("hdt")
    drive.request_state(EcState.PREOP)
    drive.request_state(EcState.SAFEOP)
    drive._store[(0x6041, 0)] = b"\x37\x16\xFF"  # one byte more than mapped: cut
    drive._store[(0x6061, 0)] = b""  # shorter: zeros
    whole = Layout(48, [(0x6041, 0, 0, 16), (0x6061, 0, 16, 8), (0, 0, 24, 8), (0x6064, 0, 32, 16)])
    bits = Layout(52, [(0x6041, 0, 0, 16), (0x6061, 0, 16, 8), (0, 0, 24, 12), (0x6064, 0, 36, 16)])
    drive._store[(0x6064, 0)] = b"\x34\x12\x00\x00"
    drive.layout[TX] = whole
    packed = drive._pack_inputs()
    assert whole.pieces() is not None and packed == b"\x37\x16\x00\x00\x34\x12"
    drive.layout[TX] = bits
    assert bits.pieces() is None
    assert drive._pack_inputs() == b"\x37\x16\x00\x00\x40\x23\x01"


def test_a_new_pdo_mapping_after_a_cycle_is_exchanged() -> None:
    """HDT: cycle with the default mapping, then map 1600h differently in PRE-OP: the next cycles place and
    take the objects where the new mapping puts them, not where the first one did."""
    drive = Drive.from_profile("hdt")
    drive.request_state(EcState.PREOP)
    drive.request_state(EcState.SAFEOP)
    drive.request_state(EcState.OP)
    out_len, in_len = drive.process_image_sizes()
    drive.exchange(struct.pack("<H", 6) + bytes(out_len - 2))
    first = drive.exchange(struct.pack("<H", 6) + bytes(out_len - 2))
    assert struct.unpack_from("<H", first)[0] & 0x6F == 0x21  # ready to switch on, statusword first
    drive.request_state(EcState.PREOP)
    # RxPDO: target position, then controlword; TxPDO: position actual value, then statusword
    for assign, index, entries in ((0x1C12, 0x1600, (0x607A0020, 0x60400010)),
                                   (0x1C13, 0x1A00, (0x60640020, 0x60410010))):
        drive.sdo_download(assign, 0, b"\x00")
        drive.sdo_download(index, 0, b"\x00")
        for sub, value in enumerate(entries, start=1):
            drive.sdo_download(index, sub, struct.pack("<I", value))
        drive.sdo_download(index, 0, bytes([len(entries)]))
        drive.sdo_download(assign, 1, struct.pack("<H", index))
        drive.sdo_download(assign, 0, b"\x01")
    drive.request_state(EcState.SAFEOP)
    drive.request_state(EcState.OP)
    assert drive.process_image_sizes() == (6, 6)
    drive.exchange(struct.pack("<iH", 1234, 6))
    back = drive.exchange(struct.pack("<iH", 1234, 6))
    assert drive.value(0x607A) == 1234 and drive.value(0x6040) == 6
    position, status = struct.unpack("<iH", back)
    assert position == drive.value(0x6064) and status == drive.value(0x6041) != 0


@given(st.fractions(), st.fractions())
def test_conversions_to_user_integers_floor_as_the_fractions_do(value: Fraction, factor: Fraction) -> None:
    assert floor_div(value, factor) == (to_int(value / factor) if factor else 0)
    units = Units(lambda index, sub: {(0x608F, 1): factor.numerator, (0x608F, 2): factor.denominator}.get((index, sub)))
    assert units.position_to_user_int(value) == to_int(units.position_to_user(value))
    assert units.velocity_to_user_int(value) == to_int(units.velocity_to_user(value))


def test_serving_freezes_the_set_up_and_stops_the_event_log_until_it_ends(monkeypatch: pytest.MonkeyPatch) -> None:
    """``serve``: while frames are answered the drives log no events and the set-up is frozen for the garbage
    collector; both are as before once it returns (the transport is replaced: no network here)."""
    from ecattool.sim.bus import raw
    from ecattool.sim.bus.serve import serve, virtual_slaves

    seen: list[tuple[bool, int]] = []

    class FakeTransport:
        answered = 7

        def __init__(self, bus: Bus, ifname: str, fault: object) -> None:
            self.bus = bus

        def serve(self, stop: object, max_frames: int | None) -> None:
            seen.append((served[0].slave.drive.record_events, gc.get_freeze_count(), served[0].slave.own_clock))

        def close(self) -> None:
            pass

    monkeypatch.setattr(raw, "RawTransport", FakeTransport)
    served = virtual_slaves([("hdt", profiles.load("hdt"))])
    assert served[0].slave.drive.record_events and gc.get_freeze_count() == 0 and not served[0].slave.own_clock
    assert serve(served, "ecat1", lambda: None) == 7
    assert len(seen) == 1 and seen[0][0] is False and seen[0][1] > 0 and seen[0][2] is True  # the drive's own clock
    assert served[0].slave.drive.record_events and gc.get_freeze_count() == 0 and not served[0].slave.own_clock


def test_put_all_stores_as_put_does_and_renews_the_version_for_factor_objects() -> None:
    drive = Drive.from_profile("hdt")
    other = Drive.from_profile("hdt")
    keys = ((0x6064, 0), (0x6041, 0), (0x6093, 1), (0x7FFF, 9))  # the last one is in no dictionary: skipped
    for values in ((-5, 0x1637, 3, 1), (1 << 40, -1, 4, 1)):
        version = drive._store.version
        drive._put_all(keys, values)
        for (index, sub), value in zip(keys[:3], values):
            other._put(index, sub, value)
            assert drive._store[(index, sub)] == other._store[(index, sub)]
        assert drive._store.version != version  # 6093h is a factor object: the unit conversions see it
        assert (0x7FFF, 9) not in drive._store
    assert drive._store[(0x6064, 0)] == b"\x00\x00\x00\x00" and drive._store[(0x6041, 0)] == b"\xff\xff"
