"""What the ESC derives from its sync manager and FMMU registers for one access: where an access splits at
sync manager boundaries, and which bytes and bits of a logical datagram each FMMU maps to which physical bytes.

Both depend only on the registers and the access's address and length, so the ESC computes them once per
(address, length) and keeps them in a :class:`Derived` tied to the SM or FMMU list it parsed from its
registers: a register write makes the ESC parse a new list, and everything derived from the old one is
forgotten with it.
"""

from __future__ import annotations

from collections.abc import Callable, Hashable, Sequence
from typing import Generic, Protocol, TypeVar

K = TypeVar("K", bound=Hashable)
V = TypeVar("V")

#: [first, end) of a piece of an access, and the sync manager whose area it is in (None: outside every SM)
Segment = tuple[int, int, "int | None"]

#: one FMMU's share of a logical datagram: (read, write, physical first byte, physical end byte, datagram first
#: byte, datagram end byte, whole bytes, bit mask, bit shift in the physical bytes, bit shift in the datagram
#: bytes). With whole bytes the shifts are 0 and both byte ranges have the same length.
Piece = tuple[bool, bool, int, int, int, int, bool, int, int, int]


class Derived(Generic[K, V]):
    """Values computed from one configuration object by key, forgotten when the configuration object is
    another one (compared by identity) and bounded to ``limit`` keys (a master addressing many places)."""

    __slots__ = ("_source", "_values", "_limit")

    def __init__(self, limit: int = 64) -> None:
        self._source: object = None
        self._values: dict[K, V] = {}
        self._limit = limit

    def get(self, source: object, key: K, compute: Callable[[], V]) -> V:
        if source is not self._source:
            self._values.clear()
            self._source = source
        value = self._values.get(key)
        if value is None:
            if len(self._values) >= self._limit:
                self._values.clear()
            value = self._values[key] = compute()
        return value


class SmArea(Protocol):
    @property
    def start(self) -> int: ...

    @property
    def length(self) -> int: ...

    @property
    def active(self) -> bool: ...


def segments(sms: Sequence[SmArea], addr: int, n: int) -> tuple[Segment, ...]:
    """Split [addr, addr+n) into pieces outside (None) and inside an active sync manager's area. Where areas
    overlap (a sync manager an earlier master left over another's area), the lower-numbered one serves the bytes:
    a master that configures SM0-SM3 (SOEM resets only those) is served by them whatever SM4-SM7 say."""
    end = addr + n
    areas = [(sm.start, sm.start + sm.length, i) for i, sm in enumerate(sms)
             if sm.active and sm.length and sm.start < end and sm.start + sm.length > addr]
    if not areas:
        return ((addr, end, None),)
    bounds = sorted({addr, end, *(max(addr, a[0]) for a in areas), *(min(end, a[1]) for a in areas)})
    cuts: list[Segment] = []
    for lo, hi in zip(bounds, bounds[1:]):
        owner = min((i for start, stop, i in areas if start <= lo and hi <= stop), default=None)
        if cuts and cuts[-1][2] == owner:
            cuts[-1] = (cuts[-1][0], hi, owner)
        else:
            cuts.append((lo, hi, owner))
    return tuple(cuts)


class FmmuMap(Protocol):
    @property
    def physical(self) -> int: ...

    @property
    def physical_bit(self) -> int: ...

    @property
    def read(self) -> bool: ...

    @property
    def write(self) -> bool: ...

    def bit_range(self) -> tuple[int, int]: ...


def pieces(fmmus: Sequence[FmmuMap], address: int, n: int) -> tuple[Piece, ...]:
    """Each FMMU's share of the ``n`` datagram bytes at logical ``address``, in FMMU order (bit granular)."""
    d0, d1 = address * 8, (address + n) * 8
    out: list[Piece] = []
    for f in fmmus:
        lb0, lb1 = f.bit_range()
        o0, o1 = max(lb0, d0), min(lb1, d1)
        if o0 >= o1:
            continue
        nbits = o1 - o0
        pbit = f.physical * 8 + f.physical_bit + (o0 - lb0)
        pbyte0, pbyte1 = pbit // 8, (pbit + nbits + 7) // 8
        dbyte0, dbyte1 = (o0 - d0) // 8, (o1 - d0 + 7) // 8
        whole = pbit % 8 == 0 and o0 % 8 == 0 and nbits % 8 == 0
        out.append((f.read, f.write, pbyte0, pbyte1, dbyte0, dbyte1, whole, (1 << nbits) - 1,
                    pbit - pbyte0 * 8, (o0 - d0) - dbyte0 * 8))
    return tuple(out)
