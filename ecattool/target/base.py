"""The target interface: where commands go (the embedded simulator, or a real master).

One slave protocol for every master (the simulator, SOEM through pysoem, KickCAT), each implemented by one
adapter module (``target.sim``, ``target.pysoem``, ``target.kickcat``): the core :class:`SlaveTarget` (identity,
SDO, state, process data, DC) that "apply" commands (``sw download``, ``commission``) talk to without knowing
whether a simulated drive or a real one answers, and the capabilities the live-bus commands read besides
(:class:`AlStatusReport`, :class:`SiiAccess`, :class:`SdoInformation`; all together :class:`LiveSlave`). What a
master's binding cannot do raises :class:`Unsupported` naming the target and what is missing
(docs/at-the-machine.md, "What each target can do"). Errors are raised as :class:`ecattool.errors.SdoAbort`,
:class:`ecattool.errors.SdoTimeout` and :class:`ecattool.errors.StateChangeError`.
"""

from __future__ import annotations

from typing import Protocol, runtime_checkable

from ecattool.errors import SdoTooLarge, TargetError
from ecattool.esi.model import Identity
from ecattool.od.model import EcState, Entry, ObjectDictionary

#: the upload bound where the object's type is not known: SOEM's own default buffer (pysoem's 256 bytes) first ...
UNKNOWN_SIZE_FIRST = 256
#: ... then, where the slave announced more, one larger try of this many bytes at the most (a segmented upload
#: never asks a master for more: the segment count is bounded by it)
UNKNOWN_SIZE_MAX = 65536


class Unsupported(TargetError):
    """The target's master binding cannot do what was asked (e.g. SII access through KickCAT's Python module)."""


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
class AlStatusReport(Protocol):
    """A slave whose master reads its AL status code register."""

    def al_status_code(self) -> int | None:
        """The AL status code register (0x0134), or None where the master does not give it."""
        ...


@runtime_checkable
class SiiAccess(Protocol):
    """A slave whose master reads and writes its SII EEPROM (:mod:`ecattool.sii.eeprom`)."""

    def sii_read(self) -> bytes:
        """The SII image, from word 0 to the end of the category list."""
        ...

    def sii_write(self, image: bytes) -> None:
        """Write ``image`` to the SII EEPROM word by word (the caller has checked it), in the order of
        :func:`ecattool.sii.eeprom.write_sequence` (the header and its CRC last)."""
        ...

    def sii_write_word(self, word: int, data: bytes) -> None:
        """Write one 16-bit word (2 bytes, little-endian) at word address ``word`` of the SII EEPROM."""
        ...


@runtime_checkable
class SdoInformation(Protocol):
    """A slave whose master reads the SDO Information service."""

    def sdo_info(self) -> ObjectDictionary:
        """The dictionary the slave describes through the SDO Information service (raises SdoAbort/Unsupported
        where it offers none)."""
        ...


@runtime_checkable
class LiveSlave(SlaveTarget, AlStatusReport, SiiAccess, SdoInformation, Protocol):
    """One slave on a live bus: the core and every capability (a master without one raises :class:`Unsupported`
    from it). The identity is the SII's (KickCAT: 1018h's, it gives no SII access)."""


@runtime_checkable
class Target(Protocol):
    """A master with slaves."""

    def slaves(self) -> list[SlaveTarget]: ...

    def close(self) -> None: ...
