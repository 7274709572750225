"""The dictionary that types a live slave's objects, from the first source that has one: the project's device,
a device library (ESI/EDS) matched by identity, the built-in family of the identity, or the slave's own SDO
Information service. Values are decoded and encoded by the entry's data type; without any dictionary the bytes
are shown as they are."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from ecattool.errors import EcatToolError, InputError
from ecattool.esi.model import Device, Identity
from ecattool.od.model import RO, Entry, ObjectCode, ObjectDictionary, OdObject
from ecattool.od.numbers import parse_int
from ecattool.od.standard import CIA301_OBJECTS
from ecattool.od.types import Kind, lookup
from ecattool.record import Record

if TYPE_CHECKING:
    from ecattool.online.library import Library, Match


class Typed(Record):
    """A slave's dictionary and where it came from: ``device`` (given: ``--device``, or the project's), ``esi`` or
    ``eds`` (the library), ``family``, ``sdo-info`` (the slave's own), ``standard`` (one CiA-301 object,
    :func:`standard_typed`), or ``none``."""

    __slots__ = ("dictionary", "source", "match", "device", "sdo_info_error")
    dictionary: ObjectDictionary
    source: str
    match: Match | None
    device: Device | None
    #: why the slave's SDO Information gave no dictionary, where it was asked and refused
    sdo_info_error: str | None

    def __init__(self, dictionary: ObjectDictionary, source: str, match: Match | None = None,
                 device: Device | None = None, sdo_info_error: str | None = None) -> None:
        self.dictionary = dictionary
        self.source = source
        self.match = match
        self.device = device
        self.sdo_info_error = sdo_info_error

    def entry(self, index: int, subindex: int) -> Entry | None:
        return self.dictionary.entry(index, subindex)


def standard_typed(index: int, subindex: int) -> Typed | None:
    """A one-entry dictionary for a CiA-301 communication object whose type is the same on every slave (1000h,
    1008h, 1018h:01 …; ``od.standard.CIA301_OBJECTS``), ``source`` "standard"; None for any other object. Reading
    one of them needs no identity, family, library or SDO Information (``sdo read 0x1018:01``)."""
    known = CIA301_OBJECTS.get((index, subindex))
    dt = lookup(known[1]) if known is not None else None
    if known is None or dt is None:
        return None
    entry = Entry(subindex, known[0], dt, dt.bits or 0, access=RO)
    od = ObjectDictionary()
    od.add(OdObject(index, known[0], ObjectCode.VAR if subindex == 0 else ObjectCode.RECORD, {subindex: entry}))
    return Typed(od, "standard")


def identify(slave: Any, library: Library | None = None) -> tuple[Identity, Match | None]:
    """The slave's identity and the library device or built-in family it matches (library first)."""
    from ecattool.online.library import family_match

    ident: Identity = slave.identity()
    match = library.match(ident) if library is not None else None
    return ident, match or family_match(ident)


def typed(slave: Any, library: Library | None = None, device: Device | None = None,
          sdo_info: bool = True) -> Typed:
    """The dictionary of ``slave`` (see the module text for the order of the sources)."""
    from ecattool.online.library import Match, family_device

    if device is not None:
        return Typed(device.dictionary, "device", Match("device", device.source, device.type_name, True), device)
    ident, match = identify(slave, library)
    if match is not None:
        dev = library.device(match) if match.kind == "esi" and library is not None else family_device(match)
        kind = "eds" if match.source.lower().endswith((".eds", ".dcf")) else match.kind
        return Typed(dev.dictionary, kind, match, dev)
    if sdo_info:
        try:
            return Typed(slave.sdo_info(), "sdo-info")
        except EcatToolError as exc:  # the slave offers no SDO Information (or the master gives none): untyped
            return Typed(ObjectDictionary(), "none", sdo_info_error=exc.message)
    return Typed(ObjectDictionary(), "none")


def decode(entry: Entry | None, data: bytes) -> Any:
    """The value of ``data`` by the entry's type; the hex string where there is no entry or it does not decode."""
    if entry is None or entry.datatype is None:
        return "0x" + data.hex() if data else ""
    try:
        value = entry.decode(data)
    except (EcatToolError, ValueError, IndexError, UnicodeDecodeError):
        return "0x" + data.hex()
    return value.hex() if isinstance(value, (bytes, bytearray)) else value


def encode(entry: Entry | None, text: str, index: int, subindex: int) -> bytes:
    """The bytes to write for ``text``: by the entry's data type (range checked), or ``hex:…`` raw bytes."""
    where = f"0x{index:04X}:{subindex:02X}"
    if text.lower().startswith("hex:"):
        try:
            return bytes.fromhex(text[4:])
        except ValueError:
            raise InputError(f"{where}: {text!r} is not hex bytes") from None
    if entry is None or entry.datatype is None:
        raise InputError(f"{where}: no dictionary types this object; give the bytes as hex:0A0B… or a --library/"
                         "--device that describes it")
    value: Any = text
    kind = entry.datatype.kind
    if kind is Kind.REAL:
        try:
            value = float(text)
        except ValueError:
            raise InputError(f"{where} ({entry.type_name}): {text!r} is not a number") from None
    elif kind is Kind.OCTETS:
        try:
            value = bytes.fromhex(text.removeprefix("0x"))
        except ValueError:
            raise InputError(f"{where} ({entry.type_name}): {text!r} is not hex bytes") from None
    elif kind not in (Kind.STRING, Kind.UNICODE):
        value = parse_int(text, what=f"value of {where}")
    try:
        return entry.encode(value)
    except EcatToolError as exc:
        raise InputError(f"{where} ({entry.type_name}): {exc}") from None
