"""The target interface: where commands go (the embedded simulator, or a real master).

"Apply" commands (``sw download``, ``commission``) talk to a :class:`SlaveTarget` and never know whether
a simulated drive or a real one answers. Errors are raised as :class:`ecattool.errors.SdoAbort`,
:class:`ecattool.errors.SdoTimeout` and :class:`ecattool.errors.StateChangeError`.
"""

from __future__ import annotations

from typing import Protocol, runtime_checkable

from ecattool.esi.model import Identity
from ecattool.od.model import EcState


@runtime_checkable
class SlaveTarget(Protocol):
    """One EtherCAT slave behind a master."""

    position: int

    def identity(self) -> Identity: ...

    def sdo_upload(self, index: int, subindex: int, complete_access: bool = False) -> bytes: ...

    def sdo_download(
        self, index: int, subindex: int, data: bytes, complete_access: bool = False, expect_reply: bool = True
    ) -> None: ...

    def state(self) -> EcState: ...

    def request_state(self, state: EcState) -> None: ...

    def exchange(self, outputs: bytes) -> bytes:
        """One process-data cycle: write the output image, return the input image."""
        ...

    def configure_dc(self, assign_activate: int, sync0_cycle_ns: int = 0, sync0_shift_ns: int = 0) -> None:
        """Distributed clocks, set by the master before SAFE-OP (AssignActivate, e.g. 0x0300 = SYNC0), the
        SYNC0 cycle and shift times in ns."""
        ...


@runtime_checkable
class Target(Protocol):
    """A master with slaves."""

    def slaves(self) -> list[SlaveTarget]: ...

    def close(self) -> None: ...
