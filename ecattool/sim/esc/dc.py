"""The local clock of an ESC's distributed clock unit: host time (ns) plus a fixed local offset, so that
every slave starts at a different local time as real slaves do and the master's offset compensation matters."""

from __future__ import annotations

import time
from collections.abc import Callable


class Clock:
    def __init__(self, offset_ns: int = 0, host: Callable[[], int] = time.monotonic_ns) -> None:
        self.offset_ns = offset_ns
        self.host = host

    def host_ns(self) -> int:
        return self.host()

    def local_ns(self, host_ns: int) -> int:
        return (host_ns + self.offset_ns) & 0xFFFFFFFFFFFFFFFF


def next_pulse(now: int, first: int, period: int) -> int:
    """The first pulse at or after ``now`` of a train starting at ``first`` with ``period`` (0: one single pulse,
    which stays the answer after it has fired)."""
    if now <= first or period <= 0:
        return first
    return first + -(-(now - first) // period) * period


def sync1_train(start: int, sync0_cycle: int, sync1_cycle: int) -> tuple[int, int]:
    """(first SYNC1 pulse, period) from the start time and the two cycle registers. SYNC1 follows SYNC0 (Beckhoff
    ESC technology, SYNC1 generation): with a SYNC1 cycle of 0 it is SYNC0; otherwise each SYNC1 pulse comes the
    SYNC1 cycle after a SYNC0 pulse, and the next one after the first SYNC0 pulse at or after it. So a SYNC1 cycle
    below the SYNC0 cycle shifts every pulse; 2 x the SYNC0 cycle gives every second one."""
    if sync1_cycle <= 0:
        return start, sync0_cycle
    if sync0_cycle <= 0:
        return start + sync1_cycle, 0
    return start + sync1_cycle, -(-sync1_cycle // sync0_cycle) * sync0_cycle
