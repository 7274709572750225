"""The datagram engine: a chain of ESCs processing EtherCAT frames as they pass (ETG.1000.4 §5.4).

Addressing: position (APxx, ARMW: the slave that sees ADP 0 is addressed; every slave increments ADP), node
(FPxx, FRMW: ADP = station address or, when enabled, alias), broadcast (Bxx: every slave, ADP incremented),
logical (LRD/LWR/LRW through the FMMUs). Working counter per slave: a read +1, a write +1; a read-write command
+1 for the read and +2 for the write (+3 where both happen); ARMW/FRMW: the addressed slave reads (+1), every
other slave writes (+1). Every slave ORs its event requests (under the event mask) into each datagram's IRQ.
"""

from __future__ import annotations

import struct
import time
from collections.abc import Callable, Sequence

from ecattool.sim.bus.frame import (DG_HEAD_SIZE, ETH_HEADER, MIN_PAYLOAD, TYPE_DATAGRAMS, Cmd, FrameError, Head,
                                    carries_datagrams, datagram_heads)
from ecattool.sim.esc import Esc
from ecattool.sim.esc import registers as R

#: cable + processing delay of one slave, in ns (a forwarding ESC with 100BASE-TX PHYs: some hundred ns)
HOP_NS = 600

# plain ints: comparing with them costs a fraction of looking up an enum member on every datagram and slave
_NOP, _LRD, _LWR, _LRW = int(Cmd.NOP), int(Cmd.LRD), int(Cmd.LWR), int(Cmd.LRW)
#: addressing of a command: by position (the slave that sees ADP 0; every slave increments ADP), by node (station
#: address or alias), broadcast (every slave; ADP incremented), or logical (through the FMMUs)
_POSITION, _NODE, _BROADCAST, _LOGICAL = range(4)
#: per command: (addressing, reads, writes, working counter of a write, read-modify-write)
_COMMANDS: dict[int, tuple[int, bool, bool, int, bool]] = {
    int(Cmd.APRD): (_POSITION, True, False, 0, False), int(Cmd.APWR): (_POSITION, False, True, 1, False),
    int(Cmd.APRW): (_POSITION, True, True, 2, False),
    int(Cmd.FPRD): (_NODE, True, False, 0, False), int(Cmd.FPWR): (_NODE, False, True, 1, False),
    int(Cmd.FPRW): (_NODE, True, True, 2, False),
    int(Cmd.BRD): (_BROADCAST, True, False, 0, False), int(Cmd.BWR): (_BROADCAST, False, True, 1, False),
    int(Cmd.BRW): (_BROADCAST, True, True, 2, False),
    _LRD: (_LOGICAL, True, False, 0, False), _LWR: (_LOGICAL, False, True, 0, False),
    _LRW: (_LOGICAL, True, True, 0, False),
    int(Cmd.ARMW): (_POSITION, True, True, 1, True), int(Cmd.FRMW): (_NODE, True, True, 1, True),
}
_EVENT_MASK = R.ECAT_EVENT_MASK
_DG_PACK = struct.Struct("<BBIHH").pack_into
_U16_PACK = struct.Struct("<H").pack_into


class Bus:
    """A line of slaves behind one master port (slave 0 first). ``process`` takes a frame as the master sent
    it and returns it as it comes back, or None when it is not an EtherCAT frame.

    The frame is answered from the ESCs' memory alone (registers, sync manager buffers, FMMU copies, mailbox
    buffers); the slave applications whose events fired while it passed (SM2 written, a SYNC0 pulse) run
    afterwards, in :meth:`run_applications`, as a drive's processor runs on its interrupt after the ESC has
    forwarded the frame. A transport calls it once the reply is on its way; ``process`` calls it itself first
    when the previous frame's applications have not run yet, so they always run before the next frame."""

    def __init__(self, escs: Sequence[Esc], *, hop_ns: int = HOP_NS,
                 clock: Callable[[], int] = time.monotonic_ns, offset: int = 0, line: int | None = None) -> None:
        """``offset``/``line``: this is a segment of a longer line served by several processes
        (:mod:`ecattool.sim.bus.split`): ``offset`` slaves come before it, ``line`` slaves in all."""
        self.escs = list(escs)
        self.hop_ns = hop_ns
        self.clock = clock
        self.offset = offset
        self.line = offset + len(self.escs) if line is None else line
        for i, esc in enumerate(self.escs):
            esc.link[0] = True
            esc.link[1] = offset + i < self.line - 1
        self.frames = 0
        #: the last frame turned back inside this segment (a closed port 1): the slaves after it never saw it
        self.turned_back = False
        #: the last frame (good or spoilt) goes on to the slaves after this segment
        self.passed_on = False
        #: a frame has passed since the applications last ran
        self.pending = False

    def _reach(self) -> int:
        """How many slaves a frame passes (it turns back at a slave whose port 1 is closed)."""
        for i, esc in enumerate(self.escs):
            if not esc.port_open(1):
                return i + 1
        return len(self.escs)

    def run_applications(self) -> None:
        """The slave applications run after the frame: each does what its events since its last run ask."""
        if self.pending:
            self.pending = False
            for esc in self.escs:
                esc.app.after_frame(esc)

    def process(self, raw: bytes | bytearray | memoryview, *, fcs_ok: bool = True,
                t0: int | None = None) -> bytes | None:
        """``t0``: host time (ns) the frame left the master, when an earlier segment took it (else now).

        The frame is answered in a copy of ``raw``: each datagram's data are a view of that copy the ESCs read
        and write in place, and only the fields a slave changes (address, IRQ, working counter, with the length
        words and the EtherCAT header as :meth:`Frame.to_bytes` writes them) are packed back; nothing is decoded
        into objects and encoded again."""
        if self.pending:
            self.run_applications()
        self.passed_on = False
        buf = bytearray(raw)
        heads: list[Head] | None = None
        if carries_datagrams(buf):
            try:
                heads = datagram_heads(buf, ETH_HEADER)
            except FrameError:
                fcs_ok = False
        elif fcs_ok:
            return None  # not an EtherCAT frame: it passes the slaves untouched (nobody answers it)
        reach = self._reach()
        escs = self.escs
        self.turned_back = reach < len(escs) or (bool(escs) and not escs[-1].port_open(1))
        self.passed_on = not self.turned_back
        if not fcs_ok or heads is None:
            # a slave that sees a bad frame counts it and spoils the frame further (the master drops it)
            for esc in escs[:reach]:
                esc.count_rx_error(0)
            return None
        self.frames += 1
        self.pending = True
        if t0 is None:
            t0 = self.clock()
        view = memoryview(buf)
        passing = [_Passing(pos, cmd, index, address, dlen, irq, wkc,
                            view[pos + DG_HEAD_SIZE:pos + DG_HEAD_SIZE + (dlen & 0x7FF)])
                   for pos, cmd, index, address, dlen, irq, wkc in heads]
        # the frame turns at the last slave it reaches: in this segment, or (as far as this process knows) at
        # the end of the line
        last = self.offset + reach - 1 if self.turned_back else self.line - 1
        hop = self.hop_ns
        general = self._datagram
        for k in range(reach):
            esc = escs[k]
            at = self.offset + k
            arrive = t0 + (at + 1) * hop
            esc.begin_frame(arrive, arrive + 2 * (last - at) * hop if at < last else None)
            mem = esc.mem
            for d in passing:
                c = d.cmd
                if c == _LRW or c == _LRD or c == _LWR:  # as in _datagram, without its look-ups
                    if mem[_EVENT_MASK] or mem[_EVENT_MASK + 1]:
                        d.irq |= esc.irq()
                    did_read, did_write = esc.logical(d.address, d.data, c != _LWR, c != _LRD)
                    if c == _LRW:
                        d.wkc += (1 if did_read else 0) + (2 if did_write else 0)
                    elif did_read or did_write:
                        d.wkc += 1
                else:
                    general(esc, d)
            esc.end_frame()
        final = len(passing) - 1
        end = 0
        for i, d in enumerate(passing):
            n = len(d.data)
            # a working counter past 0xFFFF wraps, as the ESC's 16-bit adder does
            _DG_PACK(buf, d.pos, d.cmd, d.index, d.address, n | (d.dlen & 0x4000) | (0x8000 if i < final else 0),
                     d.irq)
            end = d.pos + DG_HEAD_SIZE + n
            _U16_PACK(buf, end, d.wkc & 0xFFFF)
        end += 2
        _U16_PACK(buf, ETH_HEADER, (end - ETH_HEADER - 2) | (TYPE_DATAGRAMS << 12))
        # the first slave marks the frame as processed: bit 1 of the source MAC (locally administered)
        buf[6] |= 0x02
        # what follows the datagrams (the master's padding) goes; a short frame is padded with zeros
        return view[:end].tobytes().ljust(ETH_HEADER + MIN_PAYLOAD, b"\x00")

    @staticmethod
    def _datagram(esc: Esc, d: "_Passing") -> None:
        c = d.cmd
        if c == _NOP:
            return
        mem = esc.mem
        if mem[_EVENT_MASK] or mem[_EVENT_MASK + 1]:  # Esc.irq() is 0 under an empty mask
            d.irq |= esc.irq()
        kind = _COMMANDS.get(c)
        if kind is None:
            return  # an unknown command passes untouched
        addressing, reads, writes, write_wkc, rmw = kind
        if addressing == _LOGICAL:
            did_read, did_write = esc.logical(d.address, d.data, reads, writes)
            if c == _LRW:
                d.wkc += (1 if did_read else 0) + (2 if did_write else 0)
            elif did_read or did_write:
                d.wkc += 1
            return
        address = d.address
        adp, ado = address & 0xFFFF, (address >> 16) & 0xFFFF
        if addressing == _NODE:
            addressed = esc.addressed_fixed(adp)
        else:
            addressed = adp == 0 or addressing == _BROADCAST
            d.address = (address & 0xFFFF0000) | ((adp + 1) & 0xFFFF)
        if rmw:  # ARMW/FRMW: the addressed slave reads, every other one writes
            if addressed:
                data, ok = esc.ecat_read(ado, len(d.data))
                if ok:
                    d.data[:] = data
                    d.wkc += 1
            elif esc.ecat_write(ado, bytes(d.data)):
                d.wkc += 1
            return
        if not addressed:
            return
        incoming = bytes(d.data)
        if reads:
            data, ok = esc.ecat_read(ado, len(d.data))
            if ok:
                if addressing == _BROADCAST:  # a broadcast read ORs what each slave has into the data
                    n = len(data)
                    d.data[:] = (int.from_bytes(d.data, "little") | int.from_bytes(data, "little")).to_bytes(
                        n, "little")
                else:
                    d.data[:] = data
                d.wkc += 1
        if writes and esc.ecat_write(ado, incoming):
            d.wkc += write_wkc


class _Passing:
    """One datagram of the frame being answered: its fields as the slaves change them, its data a view of the
    frame's bytes, and where its header lies in the frame."""

    __slots__ = ("pos", "cmd", "index", "address", "dlen", "irq", "wkc", "data")

    def __init__(self, pos: int, cmd: int, index: int, address: int, dlen: int, irq: int, wkc: int,
                 data: memoryview) -> None:
        self.pos, self.cmd, self.index, self.address, self.dlen = pos, cmd, index, address, dlen
        self.irq, self.wkc, self.data = irq, wkc, data
