"""``Bus.process`` answers a frame in a copy of its bytes (each datagram's data a view the ESCs read and write in
place, only the changed header fields packed back) instead of decoding it into ``Datagram`` objects and encoding
them again. These tests compare it with the decode-and-encode way (kept here as the reference: ``parse_frame``,
the same per-datagram engine on ``Datagram`` objects, ``Frame.to_bytes``) on random frames: every command, random
addresses, reserved and circulated bits, bytes after the datagrams, short and long frames; the replies and the
ESCs' state after each frame must be the same. And the engine's port test equals the DL status it stands for."""

from __future__ import annotations

import struct

from hypothesis import given, settings
from hypothesis import strategies as st

from ecattool import profiles
from ecattool.sii.builder import build
from ecattool.sim.bus import Bus, Frame, FrameError, parse_frame
from ecattool.sim.esc import Clock, Esc
from ecattool.sim.esc import registers as R
from ecattool.sim.esc.core import _dl_status

_IMAGE = build(profiles.load("hdt")).to_bytes()
_T0 = 5_000_000_000


def _reference(bus: Bus, raw: bytes) -> bytes | None:
    """The frame path before it answered in place: decode, every slave every datagram, encode."""
    try:
        frame = parse_frame(raw)
    except FrameError:
        frame = None
        for esc in bus.escs:
            esc.count_rx_error(0)
    if frame is None:
        return None
    last = len(bus.escs) - 1
    for k, esc in enumerate(bus.escs):
        arrive = _T0 + (k + 1) * bus.hop_ns
        esc.begin_frame(arrive, arrive + 2 * (last - k) * bus.hop_ns if k < last else None)
        for d in frame.datagrams:
            bus._datagram(esc, d)  # type: ignore[arg-type]  # a Datagram has every field the engine uses
        esc.end_frame()
    src = bytes([frame.src[0] | 0x02]) + frame.src[1:]
    return Frame(frame.dst, src, frame.datagrams).to_bytes()


def _bus() -> Bus:
    escs = [Esc(_IMAGE, clock=Clock(offset_ns=i * 1_000_000_007, host=lambda: _T0)) for i in range(2)]
    bus = Bus(escs, clock=lambda: _T0)
    for i, esc in enumerate(escs):  # station addresses, process data SMs and FMMUs as a master sets them
        esc.begin_frame(_T0, None)
        esc.ecat_write(R.STATION_ADDRESS, struct.pack("<H", 0x1001 + i))
        esc.ecat_write(R.SM + 2 * R.SM_SIZE, struct.pack("<HHBBBBHHBBBB", 0x1100, 4, 0x64, 0, 1, 0,
                                                         0x1180, 4, 0x20, 0, 1, 0))
        esc.ecat_write(R.FMMU, struct.pack("<IHBBHBBBxxx", 4 * i, 4, 0, 7, 0x1100, 0, 2, 1)
                       + struct.pack("<IHBBHBBBxxx", 8 + 4 * i, 4, 0, 7, 0x1180, 0, 1, 1))
    return bus


_cmd = st.integers(0, 15)
_address = st.one_of(
    st.tuples(st.sampled_from([0, 1, 0xFFFF, 0x1001, 0x1002, 0x1003]),
              st.sampled_from([R.AL_STATUS, R.AL_CONTROL, R.DC_SYSTEM_TIME, R.DC_RECEIVE_TIME, R.STATION_ADDRESS,
                               R.ECAT_EVENT_MASK, R.ECAT_EVENT_REQUEST, R.DL_STATUS, 0x1100, 0x1180, 0x0F80]))
    .map(lambda a: a[0] | a[1] << 16),
    st.integers(0, 24), st.integers(0, 0xFFFFFFFF))
_datagram = st.tuples(_cmd, st.integers(0, 255), _address, st.binary(min_size=0, max_size=20),
                      st.integers(0, 0xFFFF), st.integers(0, 0xFF00), st.integers(0, 0x7) , st.booleans())


def _raw(datagrams: list[tuple[int, int, int, bytes, int, int, int, bool]], junk: bytes, inside: int) -> bytes:
    body = bytearray()
    for i, (cmd, index, address, data, irq, wkc, reserved, circulated) in enumerate(datagrams):
        length = len(data) | reserved << 11 | (0x4000 if circulated else 0) | (0x8000 if i < len(datagrams) - 1
                                                                                else 0)
        body += struct.pack("<BBIHH", cmd, index, address, length, irq) + data + struct.pack("<H", wkc)
    body += junk[:inside]  # inside the length the header announces, after the last datagram
    head = struct.pack("<H", len(body) | 0x1000)
    return b"\xff" * 6 + b"\x01\x02\x03\x04\x05\x06" + b"\x88\xa4" + head + bytes(body) + junk[inside:]


def _state(bus: Bus) -> list[tuple[object, ...]]:
    return [(bytes(e.mem), list(e._sm_full), e._wd_pd_since, e.al_state) for e in bus.escs]


@settings(max_examples=120, deadline=None)
@given(frames=st.lists(st.tuples(st.lists(_datagram, min_size=1, max_size=4), st.binary(max_size=30),
                                 st.integers(0, 30)), min_size=1, max_size=6))
def test_the_frame_answered_in_place_equals_decode_and_encode(
        frames: list[tuple[list[tuple[int, int, int, bytes, int, int, int, bool]], bytes, int]]) -> None:
    fast, reference = _bus(), _bus()
    for datagrams, junk, inside in frames:
        raw = _raw(datagrams, junk, inside)
        assert fast.process(raw, t0=_T0) == _reference(reference, raw)
        assert _state(fast) == _state(reference)


def test_a_short_or_spoilt_frame_is_answered_as_before() -> None:
    fast, reference = _bus(), _bus()
    lrw = _raw([(12, 1, 0, bytes(16), 0, 0, 0, False)], b"", 0)
    assert len(lrw) < 60  # the reply is padded to the Ethernet minimum, with zeros
    assert fast.process(lrw, t0=_T0) == _reference(reference, lrw)
    assert fast.process(lrw + b"\xEE" * 40, t0=_T0) == _reference(reference, lrw + b"\xEE" * 40)
    cut = lrw[:-3]  # the last datagram's working counter is missing: counted as a bad frame
    assert fast.process(cut, t0=_T0) is None and _reference(reference, cut) is None
    assert _state(fast) == _state(reference) and fast.escs[0].mem[R.RX_ERROR_COUNTER] == 1


def test_the_port_test_equals_the_dl_status() -> None:
    esc = Esc(_IMAGE)
    for setting in range(256):
        esc.mem[R.DL_CONTROL + 1] = setting
        for links in range(16):
            esc.link = [bool(links >> p & 1) for p in range(4)]
            status = _dl_status(setting, *esc.link)
            assert [esc.port_open(p) for p in range(4)] == [bool(status >> (9 + 2 * p) & 1) for p in range(4)]


# --- the register path's shortcuts ------------------------------------------------------------------
@settings(max_examples=60, deadline=None)
@given(addr=st.integers(0, 0x1010), n=st.integers(0, 40))
def test_the_writable_runs_are_the_writable_bytes(addr: int, n: int) -> None:
    from ecattool.sim.esc.core import _WRITABLE, _writable_runs

    covered = [a for lo, hi in _writable_runs(addr, addr + n) for a in range(lo, hi)]
    assert covered == [a for a in range(addr, addr + n) if a >= R.PROCESS_RAM or _WRITABLE[a]]


@settings(max_examples=40, deadline=None)
@given(time=st.integers(0, 2**64 - 1), offset=st.integers(0, 2**64 - 1))
def test_a_whole_system_time_write_compares_as_a_wider_one(time: int, offset: int) -> None:
    """SOEM writes the 8 octets of 0x0910 (the shortcut); a write from 0x090F to 0x0918 covers them too and takes
    the byte-wise way: the difference register and the system time must come out the same."""
    escs = [Esc(_IMAGE, clock=Clock(offset_ns=offset, host=lambda: _T0)) for _ in range(2)]
    payload = time.to_bytes(8, "little")
    for esc, addr, data in ((escs[0], R.DC_SYSTEM_TIME, payload),
                            (escs[1], R.DC_SYSTEM_TIME - 1, b"\x00" + payload + b"\x00")):
        esc.begin_frame(_T0, None)
        esc.ecat_write(R.DC_SYSTEM_DELAY, (offset % 1000).to_bytes(4, "little"))
        assert esc.ecat_write(addr, data)
    assert escs[0].mem[R.DC_SYSTEM_TIME:R.DC_SYSTEM_DIFFERENCE + 4] == \
        escs[1].mem[R.DC_SYSTEM_TIME:R.DC_SYSTEM_DIFFERENCE + 4]
