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
