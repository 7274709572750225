"""Run inside a private network namespace (tests/wire/test_wire_hostile.py starts it through ecattool.sim.bus.netns):
``ecattool sim serve PROJECT`` on one end of the veth pair; on the other end first a wrong master that sends
bounded bursts of hostile frames through a raw socket, then a fresh SOEM (pysoem) master that must find the bus,
take it to OP with the full working counter, and ``ecattool commission PROJECT --target pysoem`` -- all against
the same server, never restarted.

    python wire_hostile_scenario.py PROJECT SEED

The hostile kinds: EtherCAT headers whose length or type lie, datagrams cut short, unknown commands, addresses
outside the ESC's memory, random sync manager and FMMU registers (SM4 over the registers, SM4-SM7 over the
mailbox), AL control, DC and watchdog registers, bad mailbox headers, unfinished segmented SDO downloads (one
announcing 4 GiB), an unfinished FoE write and FoE data out of order. Watchdog time registers are written only
with 0 (off) and the largest values: a tiny watchdog time an earlier master leaves makes any ESC drop out of OP
under a master that does not set it (SOEM does not), on real hardware as here (docs/virtual-bus.md).

Prints one JSON document on stdout. Every loop and wait is bounded."""

from __future__ import annotations

import json
import random
import socket
import struct
import subprocess
import sys
import time
from typing import Any

from wire_pysoem_scenario import MASTER_IF, master_priority, open_preop, start_server, stop_server

from ecattool.sim.bus.frame import ETHERTYPE_ECAT, Cmd, Datagram, make_frame
from ecattool.sim.esc import registers as R

ST = 0x1001
END = 0x3000  # registers and 8 KiB process RAM: the served ESC's memory
SRC = b"\x02\x00\x00\x00\x00\x99"


class Wrong:
    """The wrong master: a raw socket on MASTER_IF that sends a frame and drains what comes back."""

    def __init__(self, seed: int) -> None:
        self.sock = socket.socket(socket.AF_PACKET, socket.SOCK_RAW, socket.htons(ETHERTYPE_ECAT))
        self.sock.bind((MASTER_IF, 0))
        self.sock.settimeout(0.02)
        self.rng = random.Random(seed)
        self.sent = self.answered = 0

    def raw(self, frame: bytes) -> bytes | None:
        self.sock.send(frame.ljust(60, b"\x00"))
        self.sent += 1
        deadline = time.monotonic() + 0.02
        answer = None
        while time.monotonic() < deadline:  # bounded: what comes back within 20 ms
            try:
                got = self.sock.recv(2048)
            except (socket.timeout, BlockingIOError):
                break
            if got[6:12] == SRC:
                answer = got
                self.answered += 1
                break
        return answer

    def one(self, dg: Datagram) -> tuple[bytes, int]:
        """One datagram; its data and working counter as they came back (nothing, 0 when no answer)."""
        back = self.raw(make_frame([dg], SRC))
        if back is None or len(back) < 16 + 10 + len(dg.data) + 2:
            return b"", 0
        data = back[26:26 + len(dg.data)]
        (wkc,) = struct.unpack_from("<H", back, 26 + len(dg.data))
        return bytes(data), wkc

    def wr(self, addr: int, data: bytes) -> int:
        return self.one(Datagram.make(Cmd.FPWR, ST, addr, data))[1]

    def rd(self, addr: int, n: int) -> bytes:
        return self.one(Datagram.make(Cmd.FPRD, ST, addr, n))[0]

    def rand(self, n: int) -> bytes:
        return bytes(self.rng.getrandbits(8) for _ in range(n))


def _sm(start: int, length: int, control: int, enable: int = 1) -> bytes:
    return struct.pack("<HHBBBB", start, length, control, 0, enable, 0)


def malformed(w: Wrong, count: int) -> None:
    """Headers that lie about the length or type, datagrams cut short, unknown commands."""
    good = make_frame([Datagram.make(Cmd.BRD, 0, R.TYPE, 2)], SRC)
    for i in range(count):
        frame = bytearray(good)
        kind = i % 6
        if kind == 0:  # the EtherCAT header's length: past the frame, 0, or odd
            struct.pack_into("<H", frame, 14, (w.rng.choice([0, 1, 0x7FF, 0x3F, 13]) & 0x7FF) | 0x1000)
        elif kind == 1:  # another type than datagrams
            struct.pack_into("<H", frame, 14, (struct.unpack_from("<H", frame, 14)[0] & 0x7FF) | w.rng.choice(
                [0x0000, 0x4000, 0xF000, 0x5000]))
        elif kind == 2:  # a datagram cut short: its length says more than the frame holds
            dg = make_frame([Datagram.make(Cmd.FPWR, ST, 0x1000, w.rand(40))], SRC)
            frame = bytearray(dg[:14 + 2 + 10 + w.rng.randrange(0, 30)])
            struct.pack_into("<H", frame, 14, 0x1000 | 52)
        elif kind == 3:  # an unknown command
            frame = bytearray(make_frame([Datagram.make(w.rng.randrange(15, 256), ST, 0x0130, 2)], SRC))
        elif kind == 4:  # the "more datagrams" bit with nothing after it
            frame[14 + 2 + 6:14 + 2 + 8] = struct.pack("<H", 2 | 0x8000)
        else:  # random bytes after a valid Ethernet header
            frame = bytearray(good[:14] + w.rand(w.rng.randrange(2, 80)))
        w.raw(bytes(frame))


def outside_memory(w: Wrong, count: int) -> None:
    for _ in range(count):
        addr = w.rng.randrange(END, 0x10000)
        n = w.rng.randrange(1, min(64, 0x10000 - addr) + 1)
        cmd = w.rng.choice([Cmd.FPWR, Cmd.FPRD, Cmd.BWR, Cmd.BRD, Cmd.APWR, Cmd.FPRW])
        adp = ST if cmd in (Cmd.FPWR, Cmd.FPRD, Cmd.FPRW) else 0
        w.one(Datagram.make(cmd, adp, addr, w.rand(n) if cmd in (Cmd.FPWR, Cmd.BWR, Cmd.APWR, Cmd.FPRW) else n))


def sm_fmmu(w: Wrong, count: int) -> None:
    # the frame that made every later SOEM find 0 slaves, and SM4-SM7 left over the mailbox and process areas
    w.one(Datagram.make(Cmd.BWR, 0, R.SM + 4 * R.SM_SIZE, _sm(0x0000, 0x1000, 0x26)))
    w.one(Datagram.make(Cmd.BWR, 0, R.SM + 5 * R.SM_SIZE, b"".join(
        _sm(0x1000, 0x400, c) for c in (0x22, 0x64, 0x20))))
    for _ in range(count):
        if w.rng.random() < 0.5:
            n = w.rng.randrange(0, 8)
            start = w.rng.choice([0, 0x0800, 0x0FF8, 0x1000, 0x1080, 0x1100, 0x2FF0, END, w.rng.randrange(0x10000)])
            data = _sm(start, w.rng.choice([0, 1, 8, 128, 0x1000, 0xFFFF]), w.rng.getrandbits(8),
                       w.rng.getrandbits(8))
            w.one(Datagram.make(Cmd.BWR, 0, R.SM + R.SM_SIZE * n, data))
        else:
            n = w.rng.randrange(0, 8)
            w.one(Datagram.make(Cmd.BWR, 0, R.FMMU + R.FMMU_SIZE * n, w.rand(16)))
        # and some process data at random logical addresses through whatever is mapped now
        if w.rng.random() < 0.3:
            w.one(Datagram.logical(w.rng.choice([Cmd.LRW, Cmd.LRD, Cmd.LWR]), w.rng.getrandbits(32), w.rand(32)))


def al_dc_watchdog(w: Wrong, count: int) -> None:
    for _ in range(count):
        pick = w.rng.random()
        if pick < 0.3:
            w.one(Datagram.make(Cmd.BWR, 0, R.AL_CONTROL, struct.pack("<H", w.rng.getrandbits(16))))
        elif pick < 0.7:
            addr = w.rng.randrange(0x0900, 0x09FF)
            w.one(Datagram.make(Cmd.BWR, 0, addr, w.rand(w.rng.randrange(1, 0x0A00 - addr + 1))))
        elif pick < 0.85:  # watchdog counters and status (cleared or read-only)
            w.one(Datagram.make(Cmd.BWR, 0, R.WD_STATUS_PD, w.rand(4)))
        else:  # watchdog divider and times: off, or the longest
            value = w.rng.choice([0, 0xFFFF])
            w.one(Datagram.make(Cmd.BWR, 0, w.rng.choice([R.WD_DIVIDER, R.WD_TIME_PDI, R.WD_TIME_PD]),
                                struct.pack("<H", value)))


def mailbox(w: Wrong, mbx: tuple[int, int, int, int]) -> dict[str, Any]:
    """Mailbox set up as a master would, PRE-OP, then bad headers and transfers left unfinished."""
    out_at, out_len, in_at, in_len = mbx
    w.one(Datagram.make(Cmd.APWR, 0, R.STATION_ADDRESS, struct.pack("<H", ST)))
    w.wr(R.AL_CONTROL, struct.pack("<H", 0x11))
    w.wr(R.SM, bytes(32))
    w.wr(R.SM, _sm(out_at, out_len, 0x26) + _sm(in_at, in_len, 0x22))
    w.wr(R.AL_CONTROL, struct.pack("<H", 0x12))
    state = 0
    for _ in range(50):  # bounded: 50 reads
        status = w.rd(R.AL_STATUS, 2)
        state = status[0] & 0x0F if status else 0
        if state == 2:
            break
    counter = 0

    def send(mtype: int, payload: bytes, length: int | None = None) -> int:
        nonlocal counter
        counter = counter % 7 + 1
        head = struct.pack("<HHBB", len(payload) if length is None else length, 0, 0, (counter << 4) | mtype)
        wkc = w.wr(out_at, (head + payload)[:out_len].ljust(out_len, b"\x00"))
        w.rd(in_at, in_len)  # take whatever answer is there (an answer left unread is the next case)
        return wkc

    room = out_len - 6
    send(3, b"\x00\x20", length=0xFFFF)  # length past the buffer
    send(0x0F, w.rand(20))  # unknown mailbox type
    send(3, b"")  # CoE without its header
    send(3, w.rand(room))
    # segmented downloads left unfinished: 4 GiB announced, and 1 MiB announced with some segments
    send(3, struct.pack("<HBHBI", 0x2000, 0x21, 0x1008, 0, 0xFFFFFFFF) + w.rand(room - 10))
    send(3, struct.pack("<HBHBI", 0x2000, 0x31, 0x1600, 0, 1 << 20) + w.rand(room - 10))
    toggle = 0
    for _ in range(5):
        send(3, struct.pack("<HB", 0x2000, toggle) + w.rand(room - 3))
        toggle ^= 0x10
    # FoE: a write request, data out of order, and a write left unfinished
    send(4, struct.pack("<BBI", 2, 0, 0) + b"FOESW_evil")
    send(4, struct.pack("<BBI", 3, 0, 7) + w.rand(room - 6))
    send(4, struct.pack("<BBI", 2, 0, 0) + b"FOESW_evil")
    for packet in range(1, 6):
        send(4, struct.pack("<BBI", 3, 0, packet) + w.rand(room - 6))
    send(4, struct.pack("<BBI", 4, 0, 99))  # an ACK of nothing
    for _ in range(10):  # requests whose answers nobody reads
        counter = counter % 7 + 1
        head = struct.pack("<HHBB", 10, 0, 0, (counter << 4) | 3)
        w.wr(out_at, (head + struct.pack("<HBHB4x", 0x2000, 0x40, 0x1018, 1)).ljust(out_len, b"\x00"))
    return {"preop": state == 2}


def fresh_soem(out: dict[str, Any]) -> None:
    """A new SOEM master: find the bus, PRE-OP, SDO, config_map, SAFE-OP, OP with the expected working counter."""
    import pysoem

    master = open_preop(out)
    try:
        out["identity"] = [[s.man, s.id, s.rev] for s in master.slaves]
        out["sdo"] = [bytes(s.sdo_read(0x1018, 1)).hex() for s in master.slaves]
        master.config_map()
        out["safeop"] = master.state_check(pysoem.SAFEOP_STATE, 2_000_000) == pysoem.SAFEOP_STATE
        master.state = pysoem.OP_STATE
        master.write_state()
        wkc = 0
        for _ in range(1000):  # bounded: at most 1000 cycles of 1 ms
            master.send_processdata()
            wkc = master.receive_processdata(2000)
            if master.state_check(pysoem.OP_STATE, 1000) == pysoem.OP_STATE:
                break
            time.sleep(0.001)
        for _ in range(20):  # some cycles in OP
            master.send_processdata()
            wkc = master.receive_processdata(2000)
            time.sleep(0.001)
        out["op"] = master.read_state() == pysoem.OP_STATE
        out["wkc"], out["expected_wkc"] = wkc, master.expected_wkc
        master.state = pysoem.INIT_STATE
        master.write_state()
        out["init"] = master.state_check(pysoem.INIT_STATE, 2_000_000) == pysoem.INIT_STATE
    finally:
        master.close()


def main(project: str, seed: int) -> dict[str, Any]:
    from ecattool.project.bus import devices_in_bus_order
    from ecattool.sim.bus.serve import virtual_slaves

    (served,) = virtual_slaves(devices_in_bus_order(project))
    words = served.slave.esc.eeprom.words(0x18, 4)
    mbx = (words[0], words[1], words[2], words[3])
    server, ready = start_server([project])
    out: dict[str, Any] = {"ready": ready}
    started = time.monotonic()
    try:
        w = Wrong(seed)
        out["hostile"] = mailbox(w, mbx)
        malformed(w, 120)
        outside_memory(w, 80)
        sm_fmmu(w, 120)
        al_dc_watchdog(w, 80)
        out["hostile"].update(mailbox(w, mbx))  # and leave a mailbox half-used again, with SM4-SM7 still there
        sm_fmmu(w, 20)
        out["hostile"]["sent"], out["hostile"]["answered"] = w.sent, w.answered
        out["alive_after_burst"] = server.poll() is None
        soem: dict[str, Any] = {}
        fresh_soem(soem)
        out["soem"] = soem
        # once more, then the whole commissioning by a new master process
        malformed(w, 30)
        sm_fmmu(w, 40)
        al_dc_watchdog(w, 30)
        w.sock.close()
        done = subprocess.run([sys.executable, "-m", "ecattool", "commission", project, "--target",
                               f"pysoem:{MASTER_IF}", "--json"], capture_output=True, text=True, timeout=240)
        out["commission"] = {"returncode": done.returncode, "stdout": done.stdout, "stderr": done.stderr[-2000:]}
    finally:
        out["server"] = stop_server(server)
    out["seconds"] = round(time.monotonic() - started, 1)
    return out


if __name__ == "__main__":
    master_priority()
    print(json.dumps(main(sys.argv[1], int(sys.argv[2]))))
