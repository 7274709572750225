"""The object dictionary model shared by the ESI reader, the drive profiles, the validators and the simulator."""

from __future__ import annotations

import re
from collections.abc import Iterator
from enum import Enum
from typing import Any

from ecattool.errors import EncodeError, Location
from ecattool.od.standard import CIA402_NAMES
from ecattool.od.types import DataType, Kind
from ecattool.record import FrozenRecord, Record, set_field

_AL_CODES = {"INIT": 1, "PREOP": 2, "BOOT": 3, "SAFEOP": 4, "OP": 8}


class EcState(str, Enum):
    """EtherCAT application-layer states (the AL control/status values are the ``code``)."""

    INIT = "INIT"
    PREOP = "PREOP"
    BOOT = "BOOT"
    SAFEOP = "SAFEOP"
    OP = "OP"

    @property
    def code(self) -> int:
        return _AL_CODES[self.value]

    @classmethod
    def parse(cls, text: str) -> "EcState":
        key = text.strip().upper().replace("-", "").replace("_", "")
        aliases = {"I": "INIT", "P": "PREOP", "PRE": "PREOP", "S": "SAFEOP", "SAFE": "SAFEOP", "O": "OP", "B": "BOOT"}
        return cls(aliases.get(key, key))


MAILBOX_STATES = frozenset({EcState.PREOP, EcState.SAFEOP, EcState.OP})

_RESTRICTION_STATES = {
    "PREOP": {EcState.PREOP},
    "SAFEOP": {EcState.SAFEOP},
    "OP": {EcState.OP},
    "PREOP_SAFEOP": {EcState.PREOP, EcState.SAFEOP},
    "PREOP_OP": {EcState.PREOP, EcState.OP},
    "SAFEOP_OP": {EcState.SAFEOP, EcState.OP},
}


def _restriction(text: str | None) -> frozenset[EcState]:
    if not text:
        return MAILBOX_STATES
    return frozenset(_RESTRICTION_STATES.get(text.strip().upper(), MAILBOX_STATES))


class Access(FrozenRecord):
    """Which EtherCAT states an entry can be read and written in (via SDO).

    Built from an ESI ``Flags/Access`` text (``ro``/``rw``/``wo``/``const``) and its optional
    ``ReadRestrictions``/``WriteRestrictions`` attributes (``PreOp``, ``PreOP_SafeOP``, ``SafeOP_OP`` …).
    """

    __slots__ = ("read", "write", "text")
    read: frozenset[EcState]
    write: frozenset[EcState]
    text: str

    def __init__(self, read: frozenset[EcState] = MAILBOX_STATES, write: frozenset[EcState] = MAILBOX_STATES,
                 text: str = "rw") -> None:
        set_field(self, "read", read)
        set_field(self, "write", write)
        set_field(self, "text", text)

    @classmethod
    def parse(cls, text: str | None, read_restrictions: str | None = None, write_restrictions: str | None = None) -> "Access":
        t = (text or "ro").strip().lower()
        readable = t in ("ro", "rw", "const", "r", "rwr", "rww")
        writable = t in ("rw", "wo", "w", "rwr", "rww")
        return cls(
            read=_restriction(read_restrictions) if readable else frozenset(),
            write=_restriction(write_restrictions) if writable else frozenset(),
            text=t,
        )

    def readable(self, state: EcState | None = None) -> bool:
        return bool(self.read) if state is None else state in self.read

    def writable(self, state: EcState | None = None) -> bool:
        return bool(self.write) if state is None else state in self.write


RO = Access.parse("ro")
RW = Access.parse("rw")
WO = Access.parse("wo")


class ObjectCode(str, Enum):
    VAR = "VAR"
    ARRAY = "ARRAY"
    RECORD = "RECORD"


def _norm_mapping(text: str | None) -> str:
    t = (text or "").strip().upper()
    r = "R" if "R" in t else ""
    x = "T" if "T" in t else ""
    return r + x


class Entry(Record):
    """One sub-index of an object. ``default`` is the encoded little-endian value, if the source gives one."""

    __slots__ = ("subindex", "name", "datatype", "bit_size", "type_name", "bit_offset", "access", "pdo_mapping",
                 "default", "minimum", "maximum", "enum", "backup", "setting", "category", "unit", "comment",
                 "location", "values")
    subindex: int
    name: str
    datatype: DataType | None
    bit_size: int
    type_name: str
    bit_offset: int
    access: Access
    pdo_mapping: str  # "", "R", "T" or "RT"
    default: bytes | None
    minimum: int | float | None
    maximum: int | float | None
    enum: dict[int, str]
    backup: bool
    setting: bool
    category: str
    unit: str
    comment: str
    location: Location | None
    #: the only values the entry takes, where its source lists them (a value list, not an interval); None: any
    #: value between minimum and maximum
    values: frozenset[int] | None

    def __init__(self, subindex: int, name: str, datatype: DataType | None, bit_size: int, type_name: str = "",
                 bit_offset: int = 0, access: Access = RO, pdo_mapping: str = "", default: bytes | None = None,
                 minimum: int | float | None = None, maximum: int | float | None = None,
                 enum: dict[int, str] | None = None, backup: bool = False, setting: bool = False,
                 category: str = "", unit: str = "", comment: str = "", location: Location | None = None,
                 values: frozenset[int] | None = None) -> None:
        self.subindex = subindex
        self.name = name
        self.datatype = datatype
        self.bit_size = bit_size
        # the type's own name unless the source gave one
        self.type_name = type_name if type_name or datatype is None else datatype.name
        self.bit_offset = bit_offset
        self.access = access
        self.pdo_mapping = _norm_mapping(pdo_mapping)
        self.default = default
        self.minimum = minimum
        self.maximum = maximum
        self.enum = {} if enum is None else enum
        self.backup = backup
        self.setting = setting
        self.category = category
        self.unit = unit
        self.comment = comment
        self.location = location
        self.values = values

    @property
    def rx_mappable(self) -> bool:
        return "R" in self.pdo_mapping

    @property
    def tx_mappable(self) -> bool:
        return "T" in self.pdo_mapping

    @property
    def byte_size(self) -> int:
        return (self.bit_size + 7) // 8

    @property
    def default_zero_or_unknown(self) -> bool:
        """No documented default, or a default of all zero bytes (a profile velocity the drive would not
        move at)."""
        return self.default is None or not any(self.default)

    @property
    def default_value(self) -> Any:
        if self.default is None or self.datatype is None:
            return None
        try:
            return self.datatype.decode(self.default, self.bit_size)
        except Exception:  # a malformed default in a vendor file is reported by checks, not here
            return None

    def encode(self, value: Any) -> bytes:
        """Encode ``value`` with this entry's exact size; raises EncodeError on type/range problems."""
        if self.datatype is None:
            raise EncodeError(f"entry {self.name!r} has an unknown data type {self.type_name!r}")
        if self.datatype.bits is None or self.datatype.kind in (Kind.BITS, Kind.BOOL):
            return self.datatype.encode(value, self.bit_size)
        return self.datatype.encode(value)

    def decode(self, data: bytes) -> Any:
        assert self.datatype is not None
        return self.datatype.decode(data, self.bit_size)


class OdObject(Record):
    __slots__ = ("index", "name", "object_code", "entries", "type_name", "category", "location")
    index: int
    name: str
    object_code: ObjectCode
    entries: dict[int, Entry]
    type_name: str
    category: str
    location: Location | None

    def __init__(self, index: int, name: str, object_code: ObjectCode, entries: dict[int, Entry] | None = None,
                 type_name: str = "", category: str = "", location: Location | None = None) -> None:
        self.index = index
        self.name = name
        self.object_code = object_code
        self.entries = {} if entries is None else entries
        self.type_name = type_name
        self.category = category
        self.location = location

    def entry(self, subindex: int) -> Entry | None:
        return self.entries.get(subindex)

    @property
    def max_subindex(self) -> int:
        return max(self.entries) if self.entries else 0

    @property
    def bit_size(self) -> int:
        return sum(e.bit_size for e in self.entries.values())

    def __iter__(self) -> Iterator[Entry]:
        return iter(sorted(self.entries.values(), key=lambda e: e.subindex))


def _name_priority(obj: "OdObject") -> tuple[int, int]:
    area = 0 if 0x6000 <= obj.index <= 0x9FFF else 1 if 0x1000 <= obj.index <= 0x1FFF else 2
    return area, obj.index


def normalize_name(name: str) -> str:
    """``Control word``, ``controlword``, ``CONTROL_WORD`` → ``controlword`` (for lookups by name)."""
    return re.sub(r"[^0-9a-z]", "", name.lower())


class ObjectDictionary:
    """Objects by index, with lookups by address and by (normalised) name."""

    __slots__ = ("_objects", "_names")

    def __init__(self, objects: dict[int, OdObject] | None = None) -> None:
        self._objects: dict[int, OdObject] = dict(objects or {})
        self._names: dict[str, tuple[int, int]] | None = None

    def add(self, obj: OdObject) -> None:
        self._objects[obj.index] = obj
        self._names = None

    def get(self, index: int) -> OdObject | None:
        return self._objects.get(index)

    def entry(self, index: int, subindex: int) -> Entry | None:
        obj = self._objects.get(index)
        return obj.entries.get(subindex) if obj is not None else None

    def find(self, name: str) -> tuple[int, int] | None:
        """Find an object or entry by name: ``controlword``, ``Modes of operation``, ``1C12 …``.

        The device's own names first (a record whose one value besides its sub-index 0 has the object's name is
        found by that name, as its value); then the CiA 402-2 name of a standard VAR object the device has (a
        vendor may call 6040h "Axis A Control word"). A VAR object's name gives (index, 0); ``object
        name/entry name`` or ``object.entry`` addresses a sub-entry. Returns None when nothing matches.
        """
        if self._names is None:
            names: dict[str, tuple[int, int]] = {}
            # where names collide (Ingenia has a vendor "Control word" at 2010h), the standard object wins:
            # device profile area 6000h-9FFFh, then communication area 1000h-1FFFh, then the rest, by index
            for obj in sorted(self._objects.values(), key=_name_priority):
                key = normalize_name(obj.name)
                if obj.object_code is ObjectCode.VAR or len(obj.entries) == 1:
                    names.setdefault(key, (obj.index, min(obj.entries) if obj.entries else 0))
                elif obj.object_code is ObjectCode.RECORD and len(obj.entries) == 2 and 0 in obj.entries:
                    # a record of one value named as its object: what a modular ESI's PDO entry makes of an object
                    # its dictionary leaves out (ETG.2001 sample: 6041h:01 "StatusWord"); the name is the value
                    (sub, entry), = ((k, e) for k, e in obj.entries.items() if k != 0)
                    if normalize_name(entry.name) == key:
                        names.setdefault(key, (obj.index, sub))
                for e in obj.entries.values():
                    names.setdefault(key + "/" + normalize_name(e.name), (obj.index, e.subindex))
            self._names = names
        n = name.replace(".", "/")
        if "/" in n:
            a, _, b = n.partition("/")
            return self._names.get(normalize_name(a) + "/" + normalize_name(b))
        key = normalize_name(n)
        found = self._names.get(key)
        if found is None and key in CIA402_NAMES:  # the standard name of an object the ESI names otherwise
            std = self._objects.get(CIA402_NAMES[key])
            if std is not None and (std.object_code is ObjectCode.VAR or len(std.entries) == 1):
                found = (std.index, min(std.entries) if std.entries else 0)
        return found

    def __contains__(self, index: object) -> bool:
        return index in self._objects

    def __iter__(self) -> Iterator[OdObject]:
        return iter(sorted(self._objects.values(), key=lambda o: o.index))

    def __len__(self) -> int:
        return len(self._objects)

    def indices(self) -> list[int]:
        return sorted(self._objects)

    def merged(self, other: "ObjectDictionary") -> "ObjectDictionary":
        """A new dictionary with ``other``'s objects added (``other`` wins on conflicts)."""
        out = ObjectDictionary(self._objects)
        for obj in other._objects.values():
            out.add(obj)
        return out
