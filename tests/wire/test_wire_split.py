"""One line served by several processes (issue 26, item 2): the segments a frame passes one after the other
answer it exactly as the whole line in one process does. Here the segments are chained in process (what
``SplitTransport`` does between processes, without the sockets); ``tests/wire/test_wire_pysoem.py`` has SOEM bring
up a line served by three processes over the wire."""

from __future__ import annotations

import struct

from ecattool.od.model import EcState
from ecattool.sim import Drive
from ecattool.sim.bus import Bus, Cmd, Datagram, make_frame, parse_frame
from ecattool.sim.bus.split import choose_workers, split
from ecattool.sim.esc import Clock
from ecattool.sim.esc import registers as R
from ecattool.sim.slave import VirtualSlave
from tests.wire.test_wire_after_frame import FakeTime, _fmmu, _outputs, _sm

PROFILES = ("hdt", "technosoft", "hdt", "controltechniques", "hdt")


class Chain:
    """Segments of one line, a frame handed from one to the next as the split transport hands it."""

    def __init__(self, segments: list[Bus]) -> None:
        self.segments = segments

    def process(self, raw: bytes, *, fcs_ok: bool = True) -> bytes | None:
        t0 = self.segments[0].clock()
        for seg in self.segments:
            reply = seg.process(raw, fcs_ok=fcs_ok, t0=t0)
            if not seg.passed_on:
                return reply
            fcs_ok = fcs_ok and reply is not None
            raw = reply if reply is not None else raw
        return None

    def run_applications(self) -> None:
        for seg in self.segments:
            seg.run_applications()


def _slaves(time: FakeTime) -> list[VirtualSlave]:
    return [VirtualSlave.from_drive(Drive.from_profile(p), clock=Clock(offset_ns=i * 1_000_000_007, host=time))
            for i, p in enumerate(PROFILES)]


def _script() -> list[bytes]:
    """Frames a master sends to bring the line up and cycle it: position addressing, broadcast, DC latch, the
    configuration of each slave by its station address, process data."""
    n = len(PROFILES)
    frames = [make_frame([Datagram.make(Cmd.BRD, 0, R.TYPE, 1)]),
              make_frame([Datagram.make(Cmd.BWR, 0, R.DC_RECEIVE_TIME, bytes(4))]),
              make_frame([Datagram.make(Cmd.APRD, (-i) & 0xFFFF, R.DC_RECEIVE_TIME, 16) for i in range(n)])]
    probe_sizes = []
    for p in PROFILES:
        d = Drive.from_profile(p)
        d.request_state(EcState.PREOP)
        d.request_state(EcState.SAFEOP)
        probe_sizes.append((d, d.process_image_sizes()))
    out_total = sum(o for _, (o, _) in probe_sizes)
    in_total = sum(i for _, (_, i) in probe_sizes)
    out_at = in_at = 0
    for i, (_, (out_len, in_len)) in enumerate(probe_sizes):
        st = 0x1001 + i
        frames.append(make_frame([Datagram.make(Cmd.APWR, (-i) & 0xFFFF, R.STATION_ADDRESS, struct.pack("<H", st))]))
        frames.append(make_frame([Datagram.make(Cmd.FPWR, st, R.SM, _sm(0x1000, 128, 0x26) + _sm(0x1080, 128, 0x22))]))
        frames.append(make_frame([Datagram.make(Cmd.FPWR, st, R.AL_CONTROL, struct.pack("<H", 2))]))
        frames.append(make_frame([Datagram.make(Cmd.FPWR, st, R.SM + 16, _sm(0x1400, out_len, 0x64)
                                                + _sm(0x1600, in_len, 0x20))]))
        frames.append(make_frame([Datagram.make(Cmd.FPWR, st, R.FMMU, _fmmu(out_at, out_len, 0x1400, 2)
                                                + _fmmu(out_total + in_at, in_len, 0x1600, 1))]))
        out_at, in_at = out_at + out_len, in_at + in_len
    for state in (4, 8):
        frames.append(make_frame([Datagram.make(Cmd.BWR, 0, R.AL_CONTROL, struct.pack("<H", state))]))
        frames.append(make_frame([Datagram.make(Cmd.BRD, 0, R.AL_STATUS, 6)]))
    for k in range(40):
        outs = b"".join(_outputs(d, o, k) for d, (o, _) in probe_sizes)
        frames.append(make_frame([Datagram.logical(Cmd.LRW, 0, outs + bytes(in_total)),
                                  Datagram.make(Cmd.FRMW, 0x1001, R.DC_SYSTEM_TIME, 8)]))
    return frames


def test_segments_answer_every_frame_as_the_whole_line_does() -> None:
    frames = _script()
    replies = {}
    for parts in (1, 2, 3, 5):
        time = FakeTime()
        slaves = _slaves(time)
        escs = [s.esc for s in slaves]
        chain = Chain([Bus([escs[i] for i in r], offset=r.start, line=len(escs), clock=time)
                       for r in split(len(escs), parts)])
        out = []
        for raw in frames:
            time.ns += 1_000_000
            out.append(chain.process(raw))
            chain.run_applications()
        assert all(r is not None for r in out)
        assert all(s.drive.state().value == "OP" for s in slaves), parts
        replies[parts] = out
        last = parse_frame(out[-1] or b"")
        assert last is not None and last.datagrams[0].wkc == 3 * len(slaves)  # every slave read and wrote
    assert replies[2] == replies[1] and replies[3] == replies[1] and replies[5] == replies[1]


def test_a_frame_turning_back_inside_a_segment_goes_no_further() -> None:
    time = FakeTime()
    escs = [s.esc for s in _slaves(time)]
    first, second = (Bus([escs[i] for i in r], offset=r.start, line=len(escs), clock=time) for r in split(5, 2))
    chain = Chain([first, second])
    assert escs[2].link[1] is True and escs[4].link[1] is False  # slave 2 ends segment 1, not the line
    escs[1].mem[R.DL_CONTROL + 1] = 0x0C  # slave 1 closes its port 1 (loop setting 3: always closed)
    raw = chain.process(make_frame([Datagram.make(Cmd.BRD, 0, R.TYPE, 1)]))
    assert raw is not None and not first.passed_on and second.frames == 0


def test_the_split_is_consecutive_and_chosen_from_drives_and_cores() -> None:
    assert split(5, 3) == [range(0, 2), range(2, 4), range(4, 5)]
    assert split(3, 8) == [range(0, 1), range(1, 2), range(2, 3)]
    assert split(16, 2) == [range(0, 8), range(8, 16)]
    assert choose_workers(8, cores=2) == 1 and choose_workers(16, cores=2) == 1 and choose_workers(17, cores=2) == 2
    assert choose_workers(40, cores=2) == 2 and choose_workers(40, cores=1) == 1 and choose_workers(1, cores=8) == 1
    assert choose_workers(40, cores=8) == 3
