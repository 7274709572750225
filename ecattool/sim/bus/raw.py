"""Raw Ethernet on a Linux interface (AF_PACKET, EtherType 0x88A4): the transport real masters talk through.

Frames are served one at a time: each EtherCAT frame received on the interface passes the :class:`Bus` and
goes back out of the same interface, as it would come back from the last slave of a line. Run it only on an
interface of a private network namespace (see :mod:`ecattool.sim.bus.netns`), never on the host's network.
"""

from __future__ import annotations

import socket
import struct
from collections.abc import Callable
from typing import TYPE_CHECKING

from ecattool.errors import TargetError
from ecattool.sim.bus.frame import ETHERTYPE_ECAT

if TYPE_CHECKING:  # annotations only: a master's state read (online.bus_state) opens a socket without the engine
    from ecattool.sim.bus.engine import Bus
    from ecattool.sim.bus.loop import FrameFault

#: the largest Ethernet frame (without FCS) the socket reads
MAX_FRAME = 1514
#: Linux: SOL_PACKET and its option PACKET_IGNORE_OUTGOING (since 4.20; Python 3.11's socket names neither)
_SOL_PACKET, _PACKET_IGNORE_OUTGOING = 263, 23
#: how long one wait for a frame lasts before the stop condition is checked again, in seconds
POLL_S = 0.2


def wait_at_most(sock: socket.socket, seconds: float) -> None:
    """Make a blocking receive on ``sock`` give up after ``seconds`` (SO_RCVTIMEO; it then raises
    BlockingIOError): a server waits for the next frame in the receive itself, one system call per frame, instead
    of in ``select`` and then the receive (on this project's virtual machines each system call and wake-up costs
    microseconds of a 1 ms cycle)."""
    sock.setblocking(True)
    whole = int(seconds)
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVTIMEO, struct.pack("@ll", whole, int((seconds - whole) * 1e6)))


def open_raw(ifname: str) -> socket.socket:
    """A raw socket bound to ``ifname`` receiving EtherCAT frames. One-line TargetError where raw sockets are
    not permitted or the interface does not exist."""
    if not hasattr(socket, "AF_PACKET"):
        raise TargetError("raw Ethernet needs Linux (AF_PACKET sockets)")
    try:
        # protocol 0 here, the EtherType with bind: Linux hooks a socket made with a protocol into the receive
        # path at once, and bind then takes the hook out again and waits for every CPU to let go of it (an RCU
        # grace period: 10-15 ms on this project's virtual machines, paid by every `sdo read`'s state read)
        sock = socket.socket(socket.AF_PACKET, socket.SOCK_RAW, 0)
    except PermissionError:
        raise TargetError("raw sockets are not permitted here: run as root or with CAP_NET_RAW, e.g. in a "
                          "private network namespace ('unshare -rn', see docs/virtual-bus.md)") from None
    try:
        sock.bind((ifname, ETHERTYPE_ECAT))
    except OSError as exc:
        sock.close()
        raise TargetError(f"cannot open interface {ifname!r}: {exc.strerror or exc}") from None
    try:
        # a socket does not receive what it sends itself, but it does receive what another socket sends out of
        # the same interface (the answers of `sim serve --workers N`, sent by the last worker): without this
        # option the first worker woke up for each of them to drop it; older kernels: dropped as before
        sock.setsockopt(_SOL_PACKET, _PACKET_IGNORE_OUTGOING, 1)
    except OSError:
        pass
    return sock


class RawTransport:
    """Serves ``bus`` on ``ifname``. ``fault`` (tests: faults over the wire) sees every frame the master sent
    before the bus does, as the in-process loop's hooks do: it may lose the frame or spoil it."""

    def __init__(self, bus: Bus, ifname: str, fault: FrameFault | None = None) -> None:
        self.bus = bus
        self.fault = fault
        self.ifname = ifname
        self.sock = open_raw(ifname)
        self.received = 0
        self.answered = 0

    def serve(self, stop: Callable[[], bool], max_frames: int | None = None) -> None:
        """Answer frames until ``stop()`` is true (checked at least every POLL_S) or ``max_frames`` frames
        were received."""
        sock = self.sock
        wait_at_most(sock, POLL_S)
        buf = bytearray(MAX_FRAME + 4)  # each frame is received into it; the bus answers in a copy
        view = memoryview(buf)
        while not stop() and (max_frames is None or self.received < max_frames):
            try:
                n, addr = sock.recvfrom_into(buf)
            except BlockingIOError:
                continue  # POLL_S without a frame: check the stop condition
            if len(addr) > 2 and addr[2] == socket.PACKET_OUTGOING:
                continue  # a frame this interface sent (our own answer seen by another tap)
            self.received += 1
            fcs_ok = True
            raw: bytes | memoryview = view[:n]
            if self.fault is not None:
                delivered, fcs_ok = self.fault(bytes(raw))
                if delivered is None:
                    continue
                raw = delivered
            self.answer(raw, fcs_ok)

    def answer(self, raw: bytes | memoryview, fcs_ok: bool) -> None:
        """One frame as the master sent it: through the bus and back out of the interface; then, the frame on
        its way back, the slave applications whose events fired run (the drives' cycles), while the master
        works with the reply, instead of before the reply."""
        reply = self.bus.process(raw, fcs_ok=fcs_ok)
        if reply is not None:
            self.sock.send(reply)
            self.answered += 1
        self.bus.run_applications()

    def close(self) -> None:
        self.sock.close()
