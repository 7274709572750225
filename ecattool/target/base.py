"""The target interface: where commands go (the embedded simulator, or a real master).

"Apply" commands (``sw download``, ``commission``) talk to a :class:`SlaveTarget` and never know whether
a simulated drive or a real one answers. Errors are raised as :class:`ecattool.errors.SdoAbort`,
:class:`ecattool.errors.SdoTimeout` and :class:`ecattool.errors.StateChangeError`.
"""

from __future__ import annotations

from typing import Protocol, runtime_checkable

from ecattool.errors import SdoTooLarge
from ecattool.esi.model import Identity
from ecattool.od.model import EcState, Entry

#: the upload bound where the object's type is not known: SOEM's own default buffer (pysoem's 256 bytes) first ...
UNKNOWN_SIZE_FIRST = 256
#: ... then, where the slave announced more, one larger try of this many bytes at the most (a segmented upload
#: never asks a master for more: the segment count is bounded by it)
UNKNOWN_SIZE_MAX = 65536


def check_upload(data: bytes, size: int | None, index: int, subindex: int, position: int | None) -> bytes:
    """``data`` when it fits the bound ``size`` (None: :data:`UNKNOWN_SIZE_MAX`), else :class:`SdoTooLarge`."""
    bound = UNKNOWN_SIZE_MAX if size is None else size
    if len(data) > bound:
        raise SdoTooLarge(index, subindex, position, bound, len(data), known=size is not None)
    return data


def entry_size(entry: Entry | None) -> int | None:
    """The most octets an upload of ``entry`` can bring: its data type's size, or the size its description gives
    it where that is larger (a string's length, an ESI's BitSize); None where neither is known (the master's
    documented bound then, :data:`UNKNOWN_SIZE_MAX`)."""
    if entry is None:
        return None
    sizes = [(bits + 7) // 8 for bits in (entry.datatype.bits if entry.datatype else None, entry.bit_size) if bits]
    return max(sizes, default=None)


@runtime_checkable
class SlaveTarget(Protocol):
    """One EtherCAT slave behind a master."""

    position: int

    def identity(self) -> Identity: ...

    def sdo_upload(self, index: int, subindex: int, complete_access: bool = False, size: int | None = None) -> bytes:
        """The object's value. ``size``: the most octets it can have (its type's, where the caller knows it); a
        reply larger than that is an :class:`SdoTooLarge` and the master is never asked for more. None: not known
        (SOEM's default buffer, then one try up to :data:`UNKNOWN_SIZE_MAX`)."""
        ...

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
