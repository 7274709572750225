"""One line of slaves served by several processes (issue 26, item 2): where one Python process cannot answer
every frame and run every drive's cycle within the master's period, the line is cut into segments of
consecutive slaves, one process each. A frame passes the segments in bus order, as it passes the slaves of a
line: the first process takes it from the interface, answers it for its slaves (a :class:`Bus` with an
``offset``), and hands the frame as it leaves its last slave to the next process over a local socket; the
process whose segment the frame turns back in (the last one, or one with a closed port) sends it out of the
interface. Each process runs its own drives' cycles after it has passed the frame on (the ESC answers, the
drive runs after), so the drives of different segments run at the same time on different cores while only
the ESCs' bookkeeping lies on the frame's way.

Between processes a frame travels as one datagram of a ``SOCK_SEQPACKET`` socket pair: 8 octets of host time
(ns, ``time.monotonic_ns`` is the same clock in every process) when the frame left the master, one octet
saying whether its checksum is still good, then the Ethernet frame.
"""

from __future__ import annotations

import math
import os
import signal
import socket
import struct
import sys
from collections.abc import Callable, Sequence
from types import FrameType

from ecattool.errors import TargetError
from ecattool.sim.bus.engine import Bus
from ecattool.sim.bus.loop import FrameFault
from ecattool.sim.bus.raw import MAX_FRAME, POLL_S, RawTransport, wait_at_most
from ecattool.sim.esc import Esc

_HEAD = struct.Struct("<Q?")
#: drives one process serves at 1 kHz on the 2-core build machine (docs/performance.md: 16 idle HDTs take ~0.5-0.7
#: ms of CPU per cycle; served by two processes their latency was higher, since the frame waits for a second
#: process to wake up, and the total CPU ~30 % more)
DRIVES_PER_PROCESS = 16


def available_cores() -> int:
    try:
        return len(os.sched_getaffinity(0))
    except (AttributeError, OSError):
        return os.cpu_count() or 1


def choose_workers(drives: int, cores: int | None = None) -> int:
    """How many processes serve ``drives``: one per DRIVES_PER_PROCESS drives, at most one per core."""
    cores = available_cores() if cores is None else cores
    return max(1, min(cores, math.ceil(drives / DRIVES_PER_PROCESS), drives))


def split(count: int, parts: int) -> list[range]:
    """``count`` slave positions cut into ``parts`` consecutive segments, the first ones one longer."""
    parts = max(1, min(parts, count))
    size, extra = divmod(count, parts)
    out, at = [], 0
    for i in range(parts):
        n = size + (1 if i < extra else 0)
        out.append(range(at, at + n))
        at += n
    return out


def _send_only(ifname: str) -> socket.socket:
    """A raw socket on ``ifname`` that only sends (protocol 0: the kernel delivers it no frames)."""
    sock = socket.socket(socket.AF_PACKET, socket.SOCK_RAW, 0)
    try:
        sock.bind((ifname, 0))
    except OSError as exc:
        sock.close()
        raise TargetError(f"cannot open interface {ifname!r}: {exc.strerror or exc}") from None
    return sock


def _priority_above(step: int) -> None:
    """Where the server runs at a real-time priority (``chrt -f 10 ecattool sim serve``), segment ``step`` runs
    ``step`` above it: a frame always moves on to a process of higher priority, which takes a core from the
    drives' cycles an earlier segment runs after passing the frame on (at one priority, SCHED_FIFO would let
    those cycles finish first, and the frame would wait for them). Nothing where it is not permitted."""
    try:
        policy = os.sched_getscheduler(0)
        if policy in (os.SCHED_FIFO, os.SCHED_RR):
            prio = os.sched_getparam(0).sched_priority + step
            os.sched_setscheduler(0, policy, os.sched_param(min(prio, os.sched_get_priority_max(policy))))
    except (AttributeError, OSError):
        pass


def _pass(bus: Bus, raw: bytes | memoryview, fcs_ok: bool, t0: int, onward: socket.socket | None,
          out: Callable[[bytes], object]) -> bool:
    """Answer ``raw`` for this segment; hand it on to the next process, or send it back to the master where it
    turns back here. True when it went anywhere."""
    reply = bus.process(raw, fcs_ok=fcs_ok, t0=t0)
    if bus.passed_on and onward is not None:
        onward.send(_HEAD.pack(t0, fcs_ok and reply is not None) + (reply if reply is not None else raw))
        return True
    if reply is not None:
        out(reply)
        return True
    return False


class SplitTransport(RawTransport):
    """Serves the slaves ``escs`` on ``ifname`` from ``len(segments)`` processes; ``segments`` are consecutive
    ranges of positions (:func:`split`). This process serves the first segment and reads the interface (the
    loop of :class:`~ecattool.sim.bus.raw.RawTransport`, ``fault`` included); the others are forked here and end
    when this one closes (or on SIGINT/SIGTERM)."""

    def __init__(self, escs: Sequence[Esc], segments: Sequence[range], ifname: str,
                 fault: FrameFault | None = None) -> None:
        if not segments or sum(len(r) for r in segments) != len(escs):
            raise ValueError("the segments must cover the slaves")
        line = len(escs)
        super().__init__(Bus([escs[i] for i in segments[0]], offset=0, line=line), ifname, fault)
        self.out = _send_only(ifname) if len(segments) > 1 else self.sock
        self.children: list[int] = []
        links = [socket.socketpair(socket.AF_UNIX, socket.SOCK_SEQPACKET) for _ in segments[1:]]
        self.onward = links[0][0] if links else None
        for j, seg in enumerate(segments[1:], start=1):
            pid = os.fork()
            if pid == 0:  # the worker of segment j: never returns into the caller's code
                code = 1
                try:
                    _priority_above(j)
                    self.sock.close()
                    for k, (a, b) in enumerate(links):
                        if k != j - 1:
                            b.close()
                        if k != j:
                            a.close()
                    code = _worker(Bus([escs[i] for i in seg], offset=seg.start, line=line), links[j - 1][1],
                                   links[j][0] if j < len(links) else None, self.out)
                finally:
                    os._exit(code)
            self.children.append(pid)
        for k, (a, b) in enumerate(links):
            b.close()
            if k:
                a.close()

    def answer(self, raw: bytes | memoryview, fcs_ok: bool) -> None:
        bus = self.bus
        try:
            if _pass(bus, raw, fcs_ok, bus.clock(), self.onward, self.out.send):
                self.answered += 1
        except (BrokenPipeError, ConnectionResetError):
            raise TargetError("a process serving the later slaves of the line has ended (see its message above)") \
                from None
        bus.run_applications()

    def close(self) -> None:
        if self.onward is not None:
            self.onward.close()  # the next process sees the end and closes its own link: all of them end
        for pid in self.children:
            try:
                os.waitpid(pid, 0)
            except ChildProcessError:
                pass
        if self.out is not self.sock:
            self.out.close()
        super().close()


def _worker(bus: Bus, inbound: socket.socket, onward: socket.socket | None, out: socket.socket) -> int:
    """A later segment's process: frames from the previous process, on to the next one (or back to the master),
    then its drives' cycles; until the previous process closes its link or a signal asks it to stop."""
    stopped = [False]

    def handler(signum: int, frame: FrameType | None) -> None:
        stopped[0] = True

    for s in (signal.SIGINT, signal.SIGTERM):
        signal.signal(s, handler)
    send = out.send
    wait_at_most(inbound, POLL_S)
    buf = bytearray(_HEAD.size + MAX_FRAME + 4)
    view = memoryview(buf)
    try:
        while not stopped[0]:
            try:
                n = inbound.recv_into(buf)
            except BlockingIOError:
                continue  # POLL_S without a frame: check whether a signal asked to stop
            if not n:
                return 0
            t0, fcs_ok = _HEAD.unpack_from(buf)
            _pass(bus, view[_HEAD.size:n], fcs_ok, t0, onward, send)
            bus.run_applications()
    except (BrokenPipeError, ConnectionResetError):
        return 0  # the next process has ended (the server is stopping)
    except Exception as exc:  # noqa: BLE001 - a worker must not die silently: one line, and the server stops
        print(f"ecattool sim serve: the process serving slaves {bus.offset}-{bus.offset + len(bus.escs) - 1} "
              f"failed: {type(exc).__name__}: {exc}", file=sys.stderr, flush=True)
        return 1
    finally:
        if onward is not None:
            onward.close()
        inbound.close()
    return 0


__all__ = ["DRIVES_PER_PROCESS", "SplitTransport", "choose_workers", "split"]
