"""The in-process transport: frames go straight from a master written in Python to a :class:`Bus` and back,
with no network. Tests and benchmarks use it; ``faults`` lets a test lose or spoil frames on the way."""

from __future__ import annotations

from collections import deque
from collections.abc import Callable

from ecattool.sim.bus.engine import Bus
from ecattool.sim.bus.frame import Datagram, make_frame, parse_frame

#: a fault hook: takes the raw frame the master sent, returns (frame to deliver or None to lose it, FCS good)
FrameFault = Callable[[bytes], tuple[bytes | None, bool]]


class Loop:
    def __init__(self, bus: Bus) -> None:
        self.bus = bus
        self._replies: deque[bytes] = deque()
        self.faults: deque[FrameFault] = deque()
        self.sent = 0

    def send(self, raw: bytes) -> None:
        """The master sends one Ethernet frame; the reply (if any) waits for :meth:`recv`."""
        self.sent += 1
        fcs_ok = True
        if self.faults:
            delivered, fcs_ok = self.faults.popleft()(raw)
            if delivered is None:
                return
            raw = delivered
        reply = self.bus.process(raw, fcs_ok=fcs_ok)
        if reply is not None:
            self._replies.append(reply)
        self.bus.run_applications()  # the frame is back at the master: the drives run after it

    def recv(self) -> bytes | None:
        return self._replies.popleft() if self._replies else None

    def transact(self, datagrams: list[Datagram]) -> list[Datagram] | None:
        """Send ``datagrams`` in one frame; the datagrams as they come back, or None when the frame is lost."""
        self.send(make_frame(datagrams))
        raw = self.recv()
        if raw is None:
            return None
        frame = parse_frame(raw)
        return frame.datagrams if frame is not None else None

    def one(self, d: Datagram) -> Datagram:
        """One datagram in its own frame (raises when the frame is lost)."""
        back = self.transact([d])
        if back is None:
            raise TimeoutError("the frame did not come back")
        return back[0]
