"""The two parts every other part of the drive application uses: the object store (:class:`ObjectStore`, the
values and their integer reads and writes) and the event log with the emergencies (:class:`EventLog`); and the
data they hold (:class:`Store`, :class:`Event`, :class:`Emergency`, the process image :class:`Layout`).

The other parts (:mod:`.sdo`, :mod:`.pdo`, :mod:`.process_data`, :mod:`.esm`, :mod:`.motion`, :mod:`.injection`,
:mod:`.family`, :mod:`.memory`) are objects :class:`~ecattool.sim.drive.facade.Drive` holds and wires together
at construction; none inherits another.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable
from dataclasses import dataclass, field
from fractions import Fraction
from typing import Any

from ecattool.errors import SdoAbort
from ecattool.esi.model import Direction
from ecattool.od.model import Entry
from ecattool.od.types import Kind
from ecattool.profiles.rules import interpolation_period_ns
from ecattool.sim.units import FACTOR_OBJECTS

RX, TX = Direction.RX, Direction.TX



def cycle_period(read_int: Callable[[int, int], int | None]) -> Fraction:
    """The process-data cycle in seconds: 60C2h (sub1 x 10^sub2) where the slave has it, else 1 ms."""
    base, exp = read_int(0x60C2, 1), read_int(0x60C2, 2)
    if base and exp is not None and -9 <= exp <= 2:
        return interpolation_period_ns(base, exp) / 10**9
    return Fraction(1, 1000)

@dataclass(frozen=True, slots=True)
class Event:
    """One thing the drive did. ``kind``: sdo_upload, sdo_download, sdo_abort, sdo_timeout, state,
    state_refused, cia402, emcy, reset, power_loss, eeprom, foe, halt, homing, motion_blocked."""

    seq: int
    kind: str
    data: dict[str, Any]


@dataclass(frozen=True, slots=True)
class Emergency:
    code: int
    register: int
    data: bytes = b"\x00" * 5

    def to_bytes(self) -> bytes:
        """The 8-byte EMCY message: code (LE), error register, 5 manufacturer bytes."""
        return self.code.to_bytes(2, "little") + bytes([self.register & 0xFF]) + self.data[:5].ljust(5, b"\x00")


#: a mapped entry of a process image: ((index, subindex), first byte, end byte, bit offset, bit length); the byte
#: bounds are -1 where the entry does not start and end on whole bytes
Slot = tuple[tuple[int, int], int, int, int, int]
#: a process image on whole bytes, piece by piece: ((index, subindex) or GAP, zero bytes of the piece's length),
#: and the pieces' lengths
Pieces = tuple[tuple[tuple[tuple[int, int], bytes], ...], tuple[int, ...]]
#: the key of a gap or dummy in :data:`Pieces` (no object has it)
GAP = (-1, -1)


@dataclass
class Layout:
    bits: int = 0
    #: (index, subindex, bit offset, bit length); index 0 = gap or dummy
    entries: list[tuple[int, int, int, int]] = field(default_factory=list)
    _derived: tuple[tuple[tuple[int, int, int, int], ...], tuple[Slot, ...], Pieces | None] = \
        field(default=((), (), ((), ())), init=False, repr=False, compare=False)

    @property
    def size(self) -> int:
        return (self.bits + 7) // 8

    def _derive(self) -> tuple[tuple[tuple[int, int, int, int], ...], tuple[Slot, ...], Pieces | None]:
        """What the cyclic exchange reads from the entries, computed again whenever they differ from what it
        was computed from."""
        key = tuple(self.entries)
        if key != self._derived[0]:
            slots: list[Slot] = []
            pieces: list[tuple[tuple[int, int], bytes]] | None = []
            position = 0
            for index, sub, offset, bits in key:
                whole = offset % 8 == 0 and bits % 8 == 0
                if index != 0:
                    slots.append(((index, sub), offset // 8, (offset + bits) // 8, offset, bits) if whole
                                 else ((index, sub), -1, -1, offset, bits))
                if pieces is not None and whole and offset == position:
                    pieces.append(((index, sub) if index != 0 else GAP, bytes(bits // 8)))
                else:
                    pieces = None
                position = offset + bits
            self._derived = (key, tuple(slots), None if pieces is None or position != self.bits
                             else (tuple(pieces), tuple(len(zeros) for _, zeros in pieces)))
        return self._derived

    def slots(self) -> tuple[Slot, ...]:
        """The mapped entries (gaps and dummies left out) with their byte bounds."""
        return self._derive()[1]

    def pieces(self) -> Pieces | None:
        """The whole image in order as pieces of whole bytes, and their lengths; None where an entry is not on
        whole bytes."""
        return self._derive()[2]


#: what :meth:`ObjectStore.put_all` keeps: the keys and the dictionary (and its length) it was made for, and per
#: key the dictionary has (its place among the values, key, byte size, mask): the keys of no factor object, then
#: those of factor objects (stored through the store's version check)
_PutSlot = tuple[int, tuple[int, int], int, int]
_PutPlan = tuple[tuple[tuple[int, int], ...], dict[tuple[int, int], Entry], int, tuple[_PutSlot, ...],
                 tuple[_PutSlot, ...]]

_VERSIONS = itertools.count(1)
#: settings the cycle reads every time and a master writes seldom: home offset 607Ch, software limits 607Dh,
#: polarity 607Eh, max profile velocity 607Fh, max motor speed 6080h. A write to one of them changes the store's version too, so the
#: cycle keeps what it made of them until then instead of reading them again
SETTING_OBJECTS = frozenset({0x607C, 0x607D, 0x607E, 0x607F, 0x6080})
#: the objects whose writes change the store's version
VERSIONED = FACTOR_OBJECTS | SETTING_OBJECTS


class Store(dict[tuple[int, int], bytes]):
    """The drive's object values by (index, subindex). ``version`` is new for every store and after every write
    to an object the unit conversions derive from (FACTOR_OBJECTS) or a setting the cycle reads (SETTING_OBJECTS),
    so what is made of them can be cached between writes.
    ``changes`` counts the writes that changed what the store holds (a value written again as it was is no
    change): the cyclic exchange compares it to know that nothing was written between two cycles."""

    __slots__ = ("version", "changes")

    def __init__(self, *args: Any) -> None:
        super().__init__(*args)
        self.version = next(_VERSIONS)
        self.changes = 0

    def __setitem__(self, key: tuple[int, int], value: bytes) -> None:
        if key[0] in VERSIONED:
            self.version = next(_VERSIONS)
        if dict.get(self, key) != value:
            self.changes += 1
        dict.__setitem__(self, key, value)  # without super(): every cycle stores its changed outputs

    def setdefault(self, key: tuple[int, int], default: bytes) -> bytes:
        self.version = next(_VERSIONS)
        self.changes += 1
        return super().setdefault(key, default)

    def __delitem__(self, key: tuple[int, int]) -> None:
        self.version = next(_VERSIONS)
        self.changes += 1
        super().__delitem__(key)

    # the other ways a dict changes, counted too (the drive does not use them; a test or a caller might)
    def update(self, *args: Any, **kwargs: Any) -> None:
        self.version = next(_VERSIONS)
        self.changes += 1
        super().update(*args, **kwargs)

    def pop(self, *args: Any) -> Any:
        self.version = next(_VERSIONS)
        self.changes += 1
        return super().pop(*args)

    def popitem(self) -> tuple[tuple[int, int], bytes]:
        self.version = next(_VERSIONS)
        self.changes += 1
        return super().popitem()

    def clear(self) -> None:
        self.version = next(_VERSIONS)
        self.changes += 1
        super().clear()

    def __ior__(self, other: Any) -> Store:  # type: ignore[override,misc]
        self.update(other)
        return self


def sdo_abort(index: int, sub: int, code: int) -> SdoAbort:
    return SdoAbort(index, sub, code)


def decode_int(e: Entry | None, raw: bytes) -> int:
    """An integer entry's value from its bytes (the entry's bit size wins over a disagreeing type name)."""
    v = int.from_bytes(raw, "little")
    if e is None or e.datatype is None:
        return v
    bits = e.bit_size or 8 * len(raw)
    v &= (1 << bits) - 1
    if e.datatype.kind is Kind.SIGNED and v >= 1 << (bits - 1):
        v -= 1 << bits
    return v


_UNKNOWN = (0, 0)


def _int_codec(e: Entry | None) -> tuple[int, int] | None:
    """:func:`decode_int` of the entry as (mask, sign bit; 0 for an unsigned entry), applied as ``v & mask``, minus
    twice the sign bit where it is set; None where the length comes from the bytes (no bit size)."""
    if e is None or e.datatype is None:
        return -1, 0
    bits = e.bit_size
    if not bits:
        return None
    return (1 << bits) - 1, (1 << (bits - 1)) if e.datatype.kind is Kind.SIGNED else 0


class ObjectStore:
    """The object store part: the values by (index, subindex), the dictionary's entries, and the integer reads and
    writes every other part makes through it (the drive binds :meth:`read_int`, :meth:`put`, :meth:`put_all` as its
    ``_read_int``, ``_put``, ``_put_all``). A power-on or a reset gives it a new store and dictionary."""

    __slots__ = ("store", "entries", "_int_codecs", "_put_plan", "_cycle_cache")

    def __init__(self) -> None:
        self.store = Store()
        #: :meth:`cycle` as made for one store at one version
        self._cycle_cache: tuple[Store | None, int, Fraction, int] = (None, 0, Fraction(1, 1000), 1_000_000)
        self.entries: dict[tuple[int, int], Entry] = {}
        #: :meth:`read_int`'s :func:`_int_codec` per key, for one dictionary (and its length)
        self._int_codecs: tuple[dict[tuple[int, int], Entry] | None, int,
                                dict[tuple[int, int], tuple[int, int] | None]] = (None, 0, {})
        self._put_plan: _PutPlan | None = None

    def cycle(self) -> tuple[Fraction, int]:
        """The process-data cycle (:func:`cycle_period`) in seconds and in whole nanoseconds (at least 1: what a
        clock counting nanoseconds paces the cycles by), made again only for another store or version (60C2h is a
        factor object: a write to it moves the version); ``sim serve`` asks every frame."""
        store = self.store
        cached = self._cycle_cache
        if cached[0] is not store or cached[1] != store.version:
            period = cycle_period(self.read_int)
            cached = self._cycle_cache = (store, store.version, period, max(1, int(period * 1_000_000_000)))
        return cached[2], cached[3]

    def read_int(self, index: int, sub: int) -> int | None:
        key = (index, sub)
        raw = self.store.get(key)
        if raw is None:
            return None
        entries = self.entries
        codecs = self._int_codecs
        if codecs[0] is not entries or codecs[1] != len(entries):
            codecs = self._int_codecs = (entries, len(entries), {})
        codec = codecs[2].get(key, _UNKNOWN)
        if codec is _UNKNOWN:
            codec = codecs[2][key] = _int_codec(entries.get(key))
        if codec is None:
            return decode_int(entries.get(key), raw)
        mask, sign = codec
        v = int.from_bytes(raw, "little") & mask
        return v - (sign << 1) if v & sign else v

    def put(self, index: int, sub: int, value: int) -> None:
        e = self.entries.get((index, sub))
        if e is None:
            return
        size = (e.bit_size + 7) >> 3  # Entry.byte_size, without the property call (every cycle, every input)
        # two's complement of a negative value through the mask (signed and unsigned entries alike)
        self.store[(index, sub)] = (value & ((1 << (size << 3)) - 1)).to_bytes(size, "little")

    def put_all(self, keys: tuple[tuple[int, int], ...], values: tuple[int, ...]) -> None:
        """:meth:`put` of each key with its value, for the keys stored every cycle: their sizes are looked up
        once per dictionary (and key set), and objects that are no factor objects skip the store's version
        check (there is nothing to renew for them)."""
        entries = self.entries
        plan = self._put_plan
        if plan is None or plan[0] is not keys or plan[1] is not entries or plan[2] != len(entries):
            plain_slots: list[tuple[int, tuple[int, int], int, int]] = []
            factor_slots: list[tuple[int, tuple[int, int], int, int]] = []
            for at, key in enumerate(keys):
                e = entries.get(key)
                if e is not None:
                    size = (e.bit_size + 7) >> 3
                    (factor_slots if key[0] in VERSIONED else plain_slots).append(
                        (at, key, size, (1 << (size << 3)) - 1))
            plan = self._put_plan = (keys, entries, len(entries), tuple(plain_slots), tuple(factor_slots))
        store = self.store
        plain = dict.__setitem__
        held = store.get
        changed = 0
        for at, key, size, mask in plan[3]:
            raw = (values[at] & mask).to_bytes(size, "little")
            if held(key) != raw:
                plain(store, key, raw)
                changed += 1
        for at, key, size, mask in plan[4]:
            store[key] = (values[at] & mask).to_bytes(size, "little")
        store.changes += changed

    def value(self, index: int, sub: int = 0) -> Any:
        """The decoded value of an entry (no SDO rules, no side effects): for tests and inspection."""
        e = self.entries.get((index, sub))
        raw = self.store[(index, sub)]
        return e.decode(raw) if e is not None and e.datatype is not None else raw


class EventLog:
    """The events and emergencies part: what the drive did (:class:`Event`, when ``record_events``) and the
    EMCY messages it sent, with the error register 1001h and the error history 1003h they set in the object
    store it is given."""

    __slots__ = ("objects", "events", "emergencies", "record_events", "seq")

    def __init__(self, objects: ObjectStore, record_events: bool = True) -> None:
        self.objects = objects
        self.events: list[Event] = []
        self.emergencies: list[Emergency] = []
        self.record_events = record_events
        self.seq = 0

    def log(self, kind: str, **data: Any) -> None:
        if self.record_events:
            self.seq += 1
            self.events.append(Event(self.seq, kind, data))

    def emcy(self, code: int, data: bytes = b"") -> Emergency:
        """Send an emergency message (and log it). Also sets 603Fh/1001h where the drive has them."""
        objects = self.objects
        register = objects.read_int(0x1001, 0) or 0
        if code:
            register |= 0x01
            register |= {0x2: 0x02, 0x3: 0x04, 0x4: 0x08, 0x8: 0x10}.get(code >> 12, 0)
            objects.put(0x1001, 0, register)
        if code and (0x1003, 1) in objects.entries:
            self._push_error_history(code)
        m = Emergency(code, register, bytes(data))
        self.emergencies.append(m)
        self.log("emcy", code=code, register=register, data=bytes(data).hex())
        return m

    def _push_error_history(self, code: int) -> None:
        """1003h: newest error in sub-index 1, older ones shifted down, sub-index 0 = count (CiA-301)."""
        objects = self.objects
        store = objects.store
        subs = sorted(s for (i, s) in objects.entries if i == 0x1003 and s > 0)
        for s in reversed(subs[1:]):
            store[(0x1003, s)] = store[(0x1003, s - 1)]
        objects.put(0x1003, 1, code)
        objects.put(0x1003, 0, min(len(subs), (objects.read_int(0x1003, 0) or 0) + 1))
