"""The virtual bus on the wire (issue 13, item 7): SDO round trips, process data at 1 kHz, frames per second.

Side by side in the same run:

* SDO round trips per second: pysoem (SOEM) reading 6064h and writing 607Ah of a drive served by
  ``ecattool sim serve`` over a veth pair, against the in-process simulator (``Drive.sdo_upload`` /
  ``sdo_download``) and python-canopen's ``RemoteNode`` -> ``LocalNode`` on python-can's virtual bus;
* process data: N drives (default 8 HDT) in OP, one LRW frame per cycle at 1 kHz for 10 s through pysoem, with
  the p50/p99 round-trip latency of a cycle (send to receive), the p50/p99 cycle start lateness and the missed
  cycles (a working counter short of the expected one, or a cycle started a whole period late), and what stalled
  the master's loop meanwhile (its collector passes, its involuntary switches, the machine's steal time);
* frames per second for one drive in OP: process data frames through the in-process loop (``Loop``, frame
  encoding and decoding included) and through pysoem over the veth pair, back to back;
* the server's time per frame: ``Bus.process`` of one LRW frame for 1 and 8 HDTs (idle, and enabled in CSP
  following a moving target) in process, what ``sim serve`` spends per frame; with ``--against DIR`` also for
  another revision's package (``git archive REV ecattool | tar -x -C DIR``), each in its own process,
  interleaved.

The wire parts run inside a private network namespace with a veth pair that the script makes itself
(``ecattool.sim.bus.netns``; never the host's interfaces). Every loop is bounded in time and count.

    .venv/bin/python benchmarks/bench_wire.py [--seconds 2] [--drives 8] [--pd-seconds 10] [--hz 1000]
        [--motion] [--cyclic-only] [--against DIR] [--json]

Needs the ``wire`` and ``bench`` extras (pysoem 1.1.13, canopen) and root (or unprivileged user namespaces).
Prints a table, and one JSON document with ``--json``.
"""

from __future__ import annotations

import argparse
import gc
import json
import os
import resource
import select
import signal
import statistics
import struct
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

from _procs import steal_s  # benchmarks/ is on sys.path as the script's folder

ROOT = Path(__file__).resolve().parent.parent
MASTER_IF, SLAVE_IF = "ecat0", "ecat1"
#: a hard bound on every count loop, whatever --seconds says
MAX_COUNT = 2_000_000


# --- in process ---------------------------------------------------------------------------------------------

def bench_canopen(seconds: float) -> dict[str, float]:
    """Expedited uploads and downloads per second, python-canopen RemoteNode -> LocalNode (virtual bus)."""
    from bench_sim import canopen_remote

    with canopen_remote("ecattool-bench-wire") as remote:
        out = {}
        for kind in ("upload", "download"):
            n, start = 0, time.perf_counter()
            while time.perf_counter() - start < seconds and n < MAX_COUNT:
                if kind == "upload":
                    remote.sdo.upload(0x607A, 0)
                else:
                    remote.sdo.download(0x607A, 0, (n & 0x7FFFFFFF).to_bytes(4, "little"))
                n += 1
            out[kind] = n / (time.perf_counter() - start)
        return out


def bench_drive(seconds: float) -> dict[str, float]:
    """Uploads of 6064h and downloads of 607Ah per second through the in-process ``Drive`` API (HDT, PRE-OP)."""
    from ecattool.od.model import EcState
    from ecattool.sim import Drive

    drive = Drive.from_profile("hdt")
    drive.request_state(EcState.PREOP)
    out = {}
    for kind in ("upload", "download"):
        n, start = 0, time.perf_counter()
        while time.perf_counter() - start < seconds and n < MAX_COUNT:
            for _ in range(1000):
                if kind == "upload":
                    drive.sdo_upload(0x6064, 0)
                else:
                    drive.sdo_download(0x607A, 0, (n & 0x7FFFFFFF).to_bytes(4, "little"))
                n += 1
            drive.events.clear()  # keep the event log from growing without bound during the run
        out[kind] = n / (time.perf_counter() - start)
    return out


def _sm(start: int, length: int, control: int) -> bytes:
    return struct.pack("<HHBBBB", start, length, control, 0, 1, 0)


def _fmmu(logical: int, length: int, physical: int, kind: int) -> bytes:
    return struct.pack("<IHBBHBBBxxx", logical, length, 0, 7, physical, 0, kind, 1)


def _bus_in_op(drives: int, motion: bool = False, host: Any = None) -> tuple[Any, list[Any], int, int]:
    """``drives`` HDTs brought to OP through the in-process loop the way a master does it (station addresses,
    mailbox SMs, PRE-OP, process data SMs and FMMUs: all outputs first, then all inputs, as SOEM maps them,
    SAFE-OP, OP). ``motion``: mode 8 (CSP) set in PRE-OP. ``host``: the slaves' host clock (ns; default the
    monotonic clock). Returns (loop, slaves, output bytes, input bytes) per drive."""
    from ecattool.od.model import EcState
    from ecattool.sim import Drive
    from ecattool.sim.bus import Bus, Cmd, Datagram
    from ecattool.sim.bus.loop import Loop
    from ecattool.sim.esc import Clock
    from ecattool.sim.esc import registers as R
    from ecattool.sim.slave import VirtualSlave

    slaves = [VirtualSlave.from_drive(Drive.from_profile("hdt"), clock=Clock(offset_ns=i * 1_000_000_007,
                                                                             host=host or time.monotonic_ns))
              for i in range(drives)]
    loop = Loop(Bus([s.esc for s in slaves]))
    probe = Drive.from_profile("hdt")  # the image sizes of the default PDO assignment, known from SAFE-OP on
    probe.request_state(EcState.PREOP)
    probe.request_state(EcState.SAFEOP)
    out_len, in_len = probe.process_image_sizes()
    for i, slave in enumerate(slaves):
        st = 0x1001 + i
        assert loop.one(Datagram.make(Cmd.APWR, (-i) & 0xFFFF, R.STATION_ADDRESS, struct.pack("<H", st))).wkc == 1

        def wr(addr: int, data: bytes) -> None:
            loop.one(Datagram.make(Cmd.FPWR, st, addr, data))  # noqa: B023 (used within the iteration)

        def al(state: int) -> int:
            wr(R.AL_CONTROL, struct.pack("<H", state))
            return int.from_bytes(bytes(loop.one(Datagram.make(Cmd.FPRD, st, R.AL_STATUS, 2)).data), "little")  # noqa: B023

        mbx_out, mbx_out_len, mbx_in, mbx_in_len = slave.esc.eeprom.words(0x18, 4)
        wr(R.SM, _sm(mbx_out, mbx_out_len, 0x26) + _sm(mbx_in, mbx_in_len, 0x22))
        assert al(2) == 2, "PRE-OP refused"
        if motion:
            slave.drive.sdo_download(0x6060, 0, b"\x08")
        slave.drive.sdo_download(0x60C2, 1, b"\x01")  # the drive's cycle is the bus cycle, 1 ms, as on the wire
        slave.drive.sdo_download(0x60C2, 2, (-3).to_bytes(1, "little", signed=True))
        wr(R.SM + 16, _sm(0x1100, out_len, 0x64) + _sm(0x1400, in_len, 0x20))
        wr(R.FMMU, _fmmu(i * out_len, out_len, 0x1100, 2) + _fmmu(drives * out_len + i * in_len, in_len, 0x1400, 1))
        assert al(4) == 4, "SAFE-OP refused"
        assert al(8) == 8, "OP refused"
    return loop, slaves, out_len, in_len


def _csp_outputs(drive: Any, out_len: int, controlword: int, position: int) -> bytes:
    """One drive's output image with the controlword and the CSP target position (607Ah) where it maps them."""
    from ecattool.esi.model import Direction

    out = bytearray(out_len)
    for index, _sub, offset, _bits in drive.layout[Direction.RX].entries:
        if index == 0x6040:
            out[offset // 8:offset // 8 + 2] = struct.pack("<H", controlword)
        elif index == 0x607A:
            out[offset // 8:offset // 8 + 4] = struct.pack("<i", position)
    return bytes(out)


def bench_bus(drives: int, seconds: float, motion: bool = False) -> dict[str, float]:
    """The server's time for one LRW frame of ``drives`` HDTs in OP, as ``sim serve`` runs it per frame:
    ``Bus.process`` (the ESCs answer) and ``Bus.run_applications`` (the drives' cycles). As in ``sim serve``,
    each drive runs on its own clock (1 ms, 60C2h set in PRE-OP) and keeps no event log; here the host time the
    drives read advances one period per frame, so every frame runs one cycle of each drive, as at 1 kHz on the
    wire. Idle drives (controlword 0) or, with ``motion``, drives enabled in CSP following a moving target. Wall
    time per frame (median and minimum over batches of 100 frames) and CPU time of the thread (minimum)."""
    from ecattool.sim.bus import Cmd, Datagram, make_frame

    host = [time.monotonic_ns()]
    loop, slaves, out_len, in_len = _bus_in_op(drives, motion, host=lambda: host[0])
    bus = loop.bus
    for s in slaves:
        s.own_clock = True  # what sim serve sets (a revision without it runs one cycle per frame anyway)
        s.drive.record_events = False

    def frame(controlword: int, position: int) -> bytes:
        outputs = b"".join(_csp_outputs(s.drive, out_len, controlword, position) for s in slaves)
        return make_frame([Datagram.logical(Cmd.LRW, 0, outputs + bytes(drives * in_len))])

    if motion:
        for controlword in (0x06, 0x07, 0x0F):  # shutdown, switch on, enable operation
            for _ in range(3):
                host[0] += 1_000_000
                bus.process(frame(controlword, 0))
        frames = [frame(0x0F, k * 10) for k in range(100)]
        assert all(s.drive.cia402_state.name == "OPERATION_ENABLED" for s in slaves)
    else:
        frames = [frame(0, 0)] * 100
    wall: list[float] = []
    cpu: list[float] = []
    reply: list[float] = []
    # since issue 26 the drives' cycles run after the reply (Bus.run_applications); an older revision runs them
    # inside Bus.process, so there the reply waits for everything
    after = getattr(bus, "run_applications", lambda: None)
    clock = time.perf_counter
    start = clock()
    while (clock() - start < seconds or len(wall) < 5) and len(wall) < MAX_COUNT:
        t0, c0 = clock(), time.thread_time()
        waited = 0.0
        for raw in frames:
            host[0] += 1_000_000
            f0 = clock()
            bus.process(raw)
            waited += clock() - f0
            after()
        wall.append((clock() - t0) / len(frames))
        cpu.append((time.thread_time() - c0) / len(frames))
        reply.append(waited / len(frames))
        for s in slaves:
            s.drive.events.clear()
    return {"drives": drives, "motion": motion, "median_us": statistics.median(wall) * 1e6,
            "min_us": min(wall) * 1e6, "cpu_min_us": min(cpu) * 1e6, "cpu_median_us": statistics.median(cpu) * 1e6,
            "reply_min_us": min(reply) * 1e6, "reply_median_us": statistics.median(reply) * 1e6,
            "frame_octets": drives * (out_len + in_len)}


#: the in-process bus measurements: (drives, motion)
BUS_CASES = ((1, False), (8, False), (8, True))


def bus_figures(seconds: float) -> list[dict[str, float]]:
    return [bench_bus(drives, seconds, motion) for drives, motion in BUS_CASES]


def bus_side_by_side(seconds: float, against: str | None, rounds: int = 3) -> dict[str, list[dict[str, float]]]:
    """:func:`bus_figures` of this checkout's package and, with ``against``, of the package in that directory
    (``git archive REV ecattool | tar -x -C DIR``), each in its own process, interleaved ``rounds`` times; per
    case the smallest minimum and the median of the medians."""
    runs: dict[str, list[list[dict[str, float]]]] = {"current": []}
    dirs = {"current": str(ROOT)}
    if against:
        runs["against"] = []
        dirs["against"] = str(Path(against).resolve())
    for _ in range(rounds):
        for who, where in dirs.items():
            env = dict(os.environ, PYTHONPATH=where)
            done = subprocess.run([sys.executable, str(Path(__file__).resolve()), "--bus-only", "--seconds",
                                   str(seconds)], capture_output=True, text=True, env=env, cwd=where, timeout=600)
            if done.returncode != 0:
                raise SystemExit(f"the bus measurement of {where} failed: {done.stderr[-2000:]}")
            runs[who].append(json.loads(done.stdout.strip().splitlines()[-1]))
    out: dict[str, list[dict[str, float]]] = {}
    for who, results in runs.items():
        out[who] = [dict(results[0][i], min_us=min(r[i]["min_us"] for r in results),
                         cpu_min_us=min(r[i]["cpu_min_us"] for r in results),
                         cpu_median_us=statistics.median(r[i]["cpu_median_us"] for r in results),
                         reply_min_us=min(r[i]["reply_min_us"] for r in results),
                         reply_median_us=statistics.median(r[i]["reply_median_us"] for r in results),
                         median_us=statistics.median(r[i]["median_us"] for r in results))
                    for i in range(len(BUS_CASES))]
    return out


def bench_loop_frames(seconds: float) -> dict[str, float]:
    """One HDT brought to OP through the in-process loop the way a master does it, then LRW process data frames
    back to back (frame built, passed through the ESC and the drive, parsed)."""
    from ecattool.sim.bus import Cmd, Datagram

    loop, (slave,), out_len, in_len = _bus_in_op(1)
    image = bytes(out_len + in_len)
    n, start = 0, time.perf_counter()
    while time.perf_counter() - start < seconds and n < MAX_COUNT:
        for _ in range(200):
            back = loop.transact([Datagram.logical(Cmd.LRW, 0, image)])
            assert back is not None and back[0].wkc == 3
            n += 1
        slave.drive.events.clear()
    return {"frames_per_s": n / (time.perf_counter() - start), "frame_octets": out_len + in_len}


# --- on the wire (inside the namespace) ---------------------------------------------------------------------

def _realtime() -> None:
    """SCHED_FIFO 10 where permitted (the same as the wire tests give the server): SOEM waits 2 ms for a frame."""
    try:
        os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(10))
    except (OSError, AttributeError):
        pass


def _start_server(sources: list[str], where: str | None = None, workers: int | None = None) -> subprocess.Popen[str]:
    """``ecattool sim serve`` of this checkout or of the package in ``where`` (``--against``), with ``--workers``."""
    env = dict(os.environ, PYTHONPATH=where or str(ROOT))
    extra = ["--workers", str(workers)] if workers else []
    server = subprocess.Popen([sys.executable, "-m", "ecattool", "sim", "serve", *sources, "--iface", SLAVE_IF,
                               *extra], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                              preexec_fn=_realtime, cwd=where or ROOT, env=env)  # -m puts the cwd first
    assert server.stdout is not None
    ready, _, _ = select.select([server.stdout], [], [], 60)
    if not ready or not server.stdout.readline():
        server.kill()
        raise SystemExit(f"the server did not get ready: {server.communicate(timeout=10)[1][-2000:]}")
    return server


def _stop_server(server: subprocess.Popen[str]) -> None:
    server.send_signal(signal.SIGTERM)
    try:
        server.communicate(timeout=20)
    except subprocess.TimeoutExpired:
        server.kill()
        server.communicate()


def _op(master: Any) -> None:
    """config_map, SAFE-OP, then OP with process data cycling (bounded: at most 2000 cycles of 1 ms)."""
    import pysoem

    master.config_map()
    if master.state_check(pysoem.SAFEOP_STATE, 2_000_000) != pysoem.SAFEOP_STATE:
        raise SystemExit("the bus did not reach SAFE-OP")
    master.state = pysoem.OP_STATE
    master.write_state()
    for _ in range(2000):
        master.send_processdata()
        master.receive_processdata(2000)
        if master.state_check(pysoem.OP_STATE, 1000) == pysoem.OP_STATE:
            return
        time.sleep(0.001)
    raise SystemExit("the bus did not reach OP")


def wire_one_drive(seconds: float) -> dict[str, Any]:
    """One HDT: SDO uploads/downloads per second in PRE-OP, then process data frames per second in OP."""
    import pysoem

    server = _start_server(["hdt"])
    out: dict[str, Any] = {}
    try:
        master = pysoem.Master()
        master.open(MASTER_IF)
        if master.config_init() != 1:
            raise SystemExit("pysoem did not find the drive")
        master.state_check(pysoem.PREOP_STATE, 2_000_000)
        slave = master.slaves[0]
        for kind in ("upload", "download"):
            n, start = 0, time.perf_counter()
            while time.perf_counter() - start < seconds and n < MAX_COUNT:
                if kind == "upload":
                    slave.sdo_read(0x6064, 0)
                else:
                    slave.sdo_write(0x607A, 0, struct.pack("<i", n & 0x7FFFFFFF))
                n += 1
            out[kind] = n / (time.perf_counter() - start)
        _op(master)
        n, lost, start = 0, 0, time.perf_counter()
        while time.perf_counter() - start < seconds and n < MAX_COUNT:
            master.send_processdata()
            if master.receive_processdata(2000) != master.expected_wkc:
                lost += 1
            n += 1
        out["frames_per_s"] = n / (time.perf_counter() - start)
        out["frames_short_wkc"] = lost
        master.state = pysoem.INIT_STATE
        master.write_state()
        master.close()
    finally:
        _stop_server(server)
    return out


class _MasterStalls:
    """What can hold the master's own loop up, recorded over the timed cycles: its garbage collector's passes
    (count and longest), the times the kernel switched it out while it could run, and the machine's steal time."""

    def __init__(self) -> None:
        self.passes = 0
        self.longest_ns = 0
        self.switches = 0
        self.steal_s = 0.0
        self._t0 = self._switches = 0
        self._steal = 0.0

    def _probe(self, phase: str, info: dict[str, int]) -> None:
        if phase == "start":
            self._t0 = time.perf_counter_ns()
        else:
            self.passes += 1
            self.longest_ns = max(self.longest_ns, time.perf_counter_ns() - self._t0)

    def __enter__(self) -> "_MasterStalls":
        self._switches = resource.getrusage(resource.RUSAGE_SELF).ru_nivcsw
        self._steal = steal_s()
        gc.callbacks.append(self._probe)
        return self

    def __exit__(self, *exc: object) -> None:
        gc.callbacks.remove(self._probe)
        self.switches = resource.getrusage(resource.RUSAGE_SELF).ru_nivcsw - self._switches
        self.steal_s = steal_s() - self._steal

    def figures(self) -> dict[str, Any]:
        return {"master_gc_passes": self.passes, "master_gc_longest_us": self.longest_ns / 1000.0,
                "master_involuntary_switches": self.switches, "steal_ms": self.steal_s * 1000.0}


def _cpu_s(pid: int) -> tuple[float, float]:
    """CPU time (user, system; s) of process ``pid`` and its children (a split server's workers) so far. The
    system time holds the kernel's share of each frame (the raw socket's receive and send, and the veth pair's
    delivery where it runs in the sender's context)."""
    tick = os.sysconf("SC_CLK_TCK")
    user = system = 0.0
    pids = [pid]
    try:
        with open(f"/proc/{pid}/task/{pid}/children") as f:
            pids += [int(p) for p in f.read().split()]
    except OSError:
        pass
    for p in pids:
        try:
            with open(f"/proc/{p}/stat") as f:
                fields = f.read().rsplit(")", 1)[1].split()
            user += int(fields[11]) / tick
            system += int(fields[12]) / tick
        except (OSError, IndexError, ValueError):
            pass
    return user, system


def _interpolation_period(hz: float) -> tuple[int, int] | None:
    """60C2h (value 1..255, power of ten) of one cycle at ``hz``; None where no such pair gives it exactly."""
    period_ns = round(1e9 / hz)
    for exponent in (-3, -4, -5, -6):
        unit = 10 ** (9 + exponent)
        if period_ns % unit == 0 and 1 <= period_ns // unit <= 255:
            return period_ns // unit, exponent
    return None


def _pct(values: list[int], q: float) -> float:
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, int(q * len(ordered)))] / 1000.0  # ns -> us


def wire_cyclic(drives: int, hz: float, seconds: float, motion: bool = False, where: str | None = None,
                workers: int | None = None, spin: bool = False) -> dict[str, Any]:
    """``drives`` HDTs in OP, one process data frame per cycle at ``hz`` for ``seconds`` (absolute deadlines,
    sleep then a short spin); latency = send to receive of a cycle's frame, lateness = start after deadline.
    In PRE-OP each drive's interpolation period 60C2h is set to the cycle, so that a drive on its own clock
    runs one cycle per frame. ``motion``: the drives are put in CSP (6060h = 8 by SDO in PRE-OP), enabled through the controlword and
    follow a target position that moves 10 units per cycle; else they stay idle (controlword 0)."""
    import pysoem

    from ecattool.od.model import EcState
    from ecattool.sim import Drive

    probe = Drive.from_profile("hdt")  # where the default mapping puts the controlword and the target position
    probe.request_state(EcState.PREOP)
    probe.request_state(EcState.SAFEOP)
    out_len = probe.process_image_sizes()[0]
    server = _start_server(["hdt"] * drives, where, workers)
    try:
        master = pysoem.Master()
        master.open(MASTER_IF)
        found = master.config_init()
        if found != drives:
            raise SystemExit(f"pysoem found {found} drives, not {drives}")
        master.state_check(pysoem.PREOP_STATE, 2_000_000)
        period = _interpolation_period(hz)
        for slave in master.slaves:
            if period is not None:  # the drive's cycle is the bus cycle, as a master sets it (HDT's default: 2 ms)
                slave.sdo_write(0x60C2, 1, bytes([period[0]]))
                slave.sdo_write(0x60C2, 2, period[1].to_bytes(1, "little", signed=True))
            if motion:
                slave.sdo_write(0x6060, 0, b"\x08")
        _op(master)
        if motion:
            for controlword in (0x06, 0x07, 0x0F):  # shutdown, switch on, enable operation
                for slave in master.slaves:
                    slave.output = _csp_outputs(probe, out_len, controlword, 0)
                for _ in range(5):
                    master.send_processdata()
                    master.receive_processdata(20_000)
                    time.sleep(0.002)
        # first the bus's own pace: frames back to back for at most 1 s (what cycle rate it could sustain)
        n, start = 0, time.perf_counter()
        while time.perf_counter() - start < 1.0 and n < MAX_COUNT:
            master.send_processdata()
            master.receive_processdata(20_000)
            n += 1
        back_to_back = n / (time.perf_counter() - start)
        period = int(1e9 / hz)
        timeout_us = max(100, period // 1000)  # a frame later than one period is a missed cycle
        cycles = int(seconds * hz)
        latency: list[int] = []
        lateness: list[int] = []
        short_wkc = overruns = 0
        missed_at: list[list[Any]] = []  # the first 50: [cycle, "late" (start, us) or "wkc" (latency, us)]
        _realtime()
        cpu0 = _cpu_s(server.pid)
        with _MasterStalls() as stalls:
            next_t = time.perf_counter_ns() + period
            for k in range(cycles):
                if motion:
                    image = _csp_outputs(probe, out_len, 0x0F, 10 * k)
                    for slave in master.slaves:
                        slave.output = image
                wait = next_t - time.perf_counter_ns()
                if wait > 200_000 and not spin:
                    time.sleep((wait - 150_000) / 1e9)
                while time.perf_counter_ns() < next_t:
                    pass
                t0 = time.perf_counter_ns()
                late = t0 - next_t
                lateness.append(late)
                if late >= period:
                    overruns += 1
                    if len(missed_at) < 50:
                        missed_at.append([k, "late", late // 1000])
                    next_t += (late // period) * period  # skip the cycles that passed, as a real-time loop would
                master.send_processdata()
                wkc = master.receive_processdata(timeout_us)
                latency.append(time.perf_counter_ns() - t0)
                if wkc != master.expected_wkc:
                    short_wkc += 1
                    if len(missed_at) < 50:
                        missed_at.append([k, "wkc", latency[-1] // 1000])
                next_t += period
        user1, system1 = _cpu_s(server.pid)
        server_user, server_system = user1 - cpu0[0], system1 - cpu0[1]
        state_ok = master.read_state() == pysoem.OP_STATE
        master.state = pysoem.INIT_STATE
        master.write_state()
        master.close()
    finally:
        _stop_server(server)
    return {"drives": drives, "hz": hz, "cycles": cycles, "motion": motion, "latency_p50_us": _pct(latency, 0.5),
            "latency_p99_us": _pct(latency, 0.99), "latency_max_us": max(latency) / 1000.0,
            "lateness_p50_us": _pct(lateness, 0.5), "lateness_p99_us": _pct(lateness, 0.99),
            "short_wkc": short_wkc, "overruns": overruns, "missed": short_wkc + overruns,
            "still_op": state_ok, "expected_wkc": master.expected_wkc, "back_to_back_per_s": back_to_back,
            "server_cpu_per_frame_us": (server_user + server_system) / cycles * 1e6,
            "server_system_per_frame_us": server_system / cycles * 1e6, "workers": workers, "server": where or "current",
            "missed_at": missed_at, **stalls.figures()}


def inside(args: argparse.Namespace) -> None:
    try:
        os.nice(-10)
    except OSError:
        pass
    out: dict[str, Any] = {"one": wire_one_drive(args.seconds)} if not args.cyclic_only else {}
    if args.drives:
        # with --against: this checkout's server and the other revision's, alternately, --rounds times each
        servers: list[str | None] = [None] + ([str(Path(args.against).resolve())] if args.against else [])
        out["cyclic"] = [wire_cyclic(args.drives, args.hz, args.pd_seconds, args.motion, where,
                                     args.workers if where is None else None, args.spin)
                         for _ in range(args.rounds) for where in servers]
    print(json.dumps(out))


def on_the_wire(args: argparse.Namespace) -> dict[str, Any] | str:
    """The wire part in its own namespace; the reason as a string where it cannot run here."""
    try:
        import pysoem  # noqa: F401
    except ImportError:
        return "pysoem is not installed (pip install 'ecattool[wire]')"
    sys.path.insert(0, str(ROOT))
    from ecattool.sim.bus import netns

    reason = netns.unavailable()
    if reason:
        return reason
    argv = [sys.executable, str(Path(__file__).resolve()), "--inside", "--seconds", str(args.seconds),
            "--drives", str(args.drives), "--hz", str(args.hz), "--pd-seconds", str(args.pd_seconds),
            "--rounds", str(args.rounds), *(["--motion"] if args.motion else []), *(["--spin"] if args.spin else []),
            *(["--cyclic-only"] if args.cyclic_only else []), *(["--against", args.against] if args.against else []),
            *(["--workers", str(args.workers)] if args.workers else [])]
    budget = 120 + 3 * args.seconds + (args.pd_seconds * 2 + 60) * args.rounds * (2 if args.against else 1)
    done = subprocess.run(netns.command(argv), capture_output=True, text=True, timeout=budget, cwd=ROOT)
    if done.returncode != 0:
        raise SystemExit(f"the wire benchmark failed: {done.stderr[-3000:]}")
    result: dict[str, Any] = json.loads(done.stdout.strip().splitlines()[-1])
    return result


def main() -> None:
    ap = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    ap.add_argument("--seconds", type=float, default=2.0, help="per SDO / frame rate measurement")
    ap.add_argument("--drives", type=int, default=8, help="drives on the cyclic bus (0: skip it)")
    ap.add_argument("--hz", type=float, default=1000.0)
    ap.add_argument("--pd-seconds", type=float, default=10.0)
    ap.add_argument("--motion", action="store_true",
                    help="cyclic bus: drives enabled in CSP following a moving target (default: idle drives)")
    ap.add_argument("--cyclic-only", action="store_true",
                    help="on the wire, only the cyclic bus (no SDO and one-drive frame rates)")
    ap.add_argument("--against", metavar="DIR",
                    help="also measure the server's time per frame with the ecattool package in DIR, interleaved")
    ap.add_argument("--workers", type=int, default=None,
                    help="cyclic bus: sim serve --workers N (default: sim serve chooses)")
    ap.add_argument("--rounds", type=int, default=1,
                    help="cyclic bus: runs of each server (with --against: alternating with the other revision)")
    ap.add_argument("--bus", action=argparse.BooleanOptionalAction, default=True,
                    help="the in-process server time per frame (default on)")
    ap.add_argument("--spin", action="store_true",
                    help="the master waits for each cycle's deadline by spinning, not sleeping (a sleeping "
                         "virtual CPU can wake milliseconds late)")
    ap.add_argument("--json", action="store_true")
    ap.add_argument("--inside", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--bus-only", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.inside:
        inside(args)
        return
    if args.bus_only:
        print(json.dumps(bus_figures(args.seconds)))
        return
    res: dict[str, Any] = {"bus": bus_side_by_side(min(args.seconds, 1.0), args.against) if args.bus else {},
                           "canopen": bench_canopen(args.seconds), "drive": bench_drive(args.seconds),
                           "loop": bench_loop_frames(args.seconds), "wire": on_the_wire(args),
                           "loadavg": os.getloadavg()}
    if args.json:
        print(json.dumps(res))
        return
    co, dr, wire = res["canopen"], res["drive"], res["wire"]
    print(f"load average {res['loadavg'][0]:.2f} {res['loadavg'][1]:.2f} {res['loadavg'][2]:.2f}, "
          f"{os.cpu_count()} CPUs")
    print("server time per LRW frame in process, us (100-frame batches): the whole frame (answer and the drives'\n"
          "  cycles) min / median, its CPU min / median, and how long the master waits for the answer min / median")
    for who, figures in res["bus"].items():
        for f in figures:
            print(f"  {who:8s} {f['drives']:.0f} HDT {'CSP moving' if f['motion'] else 'idle':10s} "
                  f"{f['min_us']:7.0f} {f['median_us']:7.0f} | {f['cpu_min_us']:7.0f} {f['cpu_median_us']:7.0f} | "
                  f"{f['reply_min_us']:7.0f} {f['reply_median_us']:7.0f}")
    print("SDO round trips/s            upload     download")
    print(f"  python-canopen LocalNode {co['upload']:10,.0f} {co['download']:12,.0f}")
    print(f"  ecattool Drive in process {dr['upload']:9,.0f} {dr['download']:12,.0f}")
    if isinstance(wire, str):
        print(f"  wire: skipped ({wire})")
    elif "one" in wire:
        one = wire["one"]
        print(f"  pysoem over veth          {one['upload']:10,.0f} {one['download']:12,.0f}")
        print(f"  wire / LocalNode          {one['upload'] / co['upload']:10.2f}x {one['download'] / co['download']:11.2f}x")
        print(f"  in process / wire         {dr['upload'] / one['upload']:10.0f}x {dr['download'] / one['download']:11.0f}x")
    print("frames/s, one drive in OP (LRW process data)")
    print(f"  in-process loop           {res['loop']['frames_per_s']:10,.0f}")
    if not isinstance(wire, str) and "one" in wire:
        print(f"  pysoem over veth          {wire['one']['frames_per_s']:10,.0f}"
              f"  (short working counter: {wire['one']['frames_short_wkc']})")
    if not isinstance(wire, str):
        for cyc in wire.get("cyclic", []):
            print(f"process data, {cyc['drives']} drives at {cyc['hz']:.0f} Hz, {cyc['cycles']} cycles, "
                  f"{'enabled in CSP, moving' if cyc['motion'] else 'idle'}; server {cyc['server']}, "
                  f"workers {cyc['workers'] or 'chosen'}; server CPU {cyc['server_cpu_per_frame_us']:.0f} us/frame "
                  f"({cyc['server_system_per_frame_us']:.0f} in the kernel)")
            print(f"  latency p50 {cyc['latency_p50_us']:.0f} us, p99 {cyc['latency_p99_us']:.0f} us, "
                  f"max {cyc['latency_max_us']:.0f} us; start lateness p50 {cyc['lateness_p50_us']:.0f} us, "
                  f"p99 {cyc['lateness_p99_us']:.0f} us")
            print(f"  missed cycles {cyc['missed']} (short working counter {cyc['short_wkc']}, "
                  f"overruns {cyc['overruns']}); still in OP: {cyc['still_op']}")
            print(f"  the master's stalls: {cyc['master_gc_passes']} collector passes (longest "
                  f"{cyc['master_gc_longest_us']:.0f} us), {cyc['master_involuntary_switches']} involuntary switches; "
                  f"the machine's steal time {cyc['steal_ms']:.0f} ms")
            print(f"  back to back: {cyc['back_to_back_per_s']:,.0f} cycles/s")


if __name__ == "__main__":
    main()
