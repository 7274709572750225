"""CoE data types: codes, names, bit sizes, and value encoding to little-endian bytes.

The registry covers every standard CoE/CiA-301 type plus the aliases that real ESI files use
(``USINT``, ``UINT32``, ``DINT32``, ``BIT2``, ``STRING(8)``, …). :func:`lookup` resolves a name or code to a
:class:`DataType`; :meth:`DataType.encode` and :meth:`DataType.decode` convert values with range checks.
"""

from __future__ import annotations

import math
import re
import struct
from enum import Enum
from typing import Any

from ecattool.errors import EncodeError
from ecattool.record import FrozenRecord, set_field


class Kind(str, Enum):
    BOOL = "bool"
    UNSIGNED = "unsigned"
    SIGNED = "signed"
    REAL = "real"
    BITS = "bits"  # BITn / BITARRn / BYTE / WORD / DWORD: unsigned bit fields
    STRING = "string"  # VISIBLE_STRING
    UNICODE = "unicode"
    OCTETS = "octets"  # OCTET_STRING, DOMAIN, GUID, TIME_OF_DAY …


class DataType(FrozenRecord):
    """A CoE data type. ``bits`` is None for variable-length types (strings, domains)."""

    __slots__ = ("code", "name", "kind", "bits")
    code: int
    name: str
    kind: Kind
    bits: int | None

    def __init__(self, code: int, name: str, kind: Kind, bits: int | None) -> None:
        set_field(self, "code", code)
        set_field(self, "name", name)
        set_field(self, "kind", kind)
        set_field(self, "bits", bits)

    # --- properties -------------------------------------------------------------------------
    @property
    def is_bit_type(self) -> bool:
        """BOOL and BITn: types that may legally occupy less than a byte in a PDO."""
        return self.kind is Kind.BOOL or (self.kind is Kind.BITS and self.bits is not None and self.bits < 8)

    @property
    def is_numeric(self) -> bool:
        return self.kind in (Kind.BOOL, Kind.UNSIGNED, Kind.SIGNED, Kind.REAL, Kind.BITS)

    def range(self, bits: int | None = None) -> tuple[int, int] | None:
        """Integer range (inclusive) of this type, or None for non-integer types."""
        n = bits or self.bits
        if n is None:
            return None
        if self.kind in (Kind.UNSIGNED, Kind.BITS, Kind.BOOL):
            return 0, (1 << n) - 1
        if self.kind is Kind.SIGNED:
            return -(1 << (n - 1)), (1 << (n - 1)) - 1
        return None

    # --- encoding ---------------------------------------------------------------------------
    def encode(self, value: Any, bits: int | None = None) -> bytes:
        """Encode ``value`` as little-endian bytes of this type's exact size.

        ``bits`` overrides the size for variable-length types (strings get padded/checked to it).
        Raises :class:`EncodeError` when the value does not fit.
        """
        n = self.bits if self.bits is not None else bits
        if isinstance(value, bool) and self.kind is not Kind.BOOL:  # true/false: never a number
            raise EncodeError(f"{str(value).lower()} is a boolean, not a value of {self.name}")
        if self.kind is Kind.REAL:
            try:
                f = float(value)
            except (TypeError, ValueError):
                raise EncodeError(f"{value!r} is not a number for {self.name}") from None
            if self.bits == 32:
                if math.isfinite(f) and abs(f) > 3.4028234663852886e38:
                    raise EncodeError(f"{value!r} is out of range for {self.name}")
                return struct.pack("<f", f)
            return struct.pack("<d", f)
        if self.kind in (Kind.STRING, Kind.UNICODE, Kind.OCTETS):
            if isinstance(value, (bytes, bytearray)):
                raw = bytes(value)
            elif self.kind is Kind.STRING and isinstance(value, str):
                try:
                    raw = value.encode("latin-1")
                except UnicodeEncodeError:
                    raise EncodeError(f"{value!r} has characters outside Latin-1 for {self.name}") from None
            elif self.kind is Kind.UNICODE and isinstance(value, str):
                raw = value.encode("utf-16-le")
            elif self.kind is Kind.OCTETS and isinstance(value, str):
                try:
                    raw = bytes.fromhex(value.replace(" ", ""))
                except ValueError:
                    raise EncodeError(f"{value!r} is not hex bytes for {self.name}") from None
            elif self.kind is Kind.OCTETS and isinstance(value, int) and n:
                return _encode_int(value, n, False, self.name)
            else:
                raise EncodeError(f"{value!r} cannot be encoded as {self.name}")
            if n is not None:
                size = (n + 7) // 8
                if len(raw) > size:
                    raise EncodeError(f"{len(raw)} bytes do not fit {self.name} of {size} bytes")
                raw = raw.ljust(size, b"\x00")
            return raw
        # integers and bit fields
        if isinstance(value, bool):
            value = int(value)
        if isinstance(value, float):
            if not value.is_integer():
                raise EncodeError(f"{value!r} is not an integer for {self.name}")
            value = int(value)
        if not isinstance(value, int):
            raise EncodeError(f"{value!r} is not an integer for {self.name}")
        assert n is not None
        return _encode_int(value, n, self.kind is Kind.SIGNED, self.name)

    def decode(self, data: bytes, bits: int | None = None) -> Any:
        """Decode little-endian bytes into a Python value (int, float, str or bytes)."""
        n = self.bits if self.bits is not None else bits
        if self.kind is Kind.REAL:
            if len(data) != (self.bits or 0) // 8:
                raise EncodeError(f"{len(data)} bytes is not the size of {self.name}")
            return struct.unpack("<f" if self.bits == 32 else "<d", data)[0]
        if self.kind is Kind.STRING:
            return data.split(b"\x00", 1)[0].decode("latin-1")
        if self.kind is Kind.UNICODE:
            return data.decode("utf-16-le", errors="replace").split("\x00", 1)[0]
        if self.kind is Kind.OCTETS:
            return bytes(data)
        assert n is not None
        size = (n + 7) // 8
        if len(data) != size:
            raise EncodeError(f"{len(data)} bytes is not the size of {self.name} ({size} bytes)")
        raw = int.from_bytes(data, "little", signed=False)
        if n % 8:
            raw &= (1 << n) - 1
        if self.kind is Kind.SIGNED and raw >= 1 << (n - 1):
            raw -= 1 << n
        return raw

    def __str__(self) -> str:
        return self.name


def _encode_int(value: int, bits: int, signed: bool, name: str) -> bytes:
    lo, hi = (-(1 << (bits - 1)), (1 << (bits - 1)) - 1) if signed else (0, (1 << bits) - 1)
    if not lo <= value <= hi:
        raise EncodeError(f"{value} is out of range {lo}..{hi} for {name}")
    size = (bits + 7) // 8
    return (value & ((1 << (size * 8)) - 1)).to_bytes(size, "little")


# --------------------------------------------------------------------------------------------
# The registry
# --------------------------------------------------------------------------------------------

_STANDARD: list[tuple[int, str, Kind, int | None, tuple[str, ...]]] = [
    (0x0001, "BOOL", Kind.BOOL, 1, ("BOOLEAN", "BIT")),
    (0x0002, "SINT", Kind.SIGNED, 8, ("INTEGER8", "INT8")),
    (0x0003, "INT", Kind.SIGNED, 16, ("INTEGER16", "INT16")),
    (0x0004, "DINT", Kind.SIGNED, 32, ("INTEGER32", "INT32", "DINT32")),
    (0x0005, "USINT", Kind.UNSIGNED, 8, ("UNSIGNED8", "UINT8")),
    (0x0006, "UINT", Kind.UNSIGNED, 16, ("UNSIGNED16", "UINT16")),
    (0x0007, "UDINT", Kind.UNSIGNED, 32, ("UNSIGNED32", "UINT32", "UDINT32")),
    (0x0008, "REAL", Kind.REAL, 32, ("REAL32", "FLOAT")),
    (0x0009, "STRING", Kind.STRING, None, ("VISIBLE_STRING", "VISIBLESTRING")),
    (0x000A, "OCTET_STRING", Kind.OCTETS, None, ("OCTETSTRING", "ARRAY OF BYTE")),
    (0x000B, "UNICODE_STRING", Kind.UNICODE, None, ("UNICODESTRING", "WSTRING")),
    (0x000C, "TIME_OF_DAY", Kind.OCTETS, 48, ("TOD",)),
    (0x000D, "TIME_DIFFERENCE", Kind.OCTETS, 48, ("TIME_DIFF",)),
    (0x000F, "DOMAIN", Kind.OCTETS, None, ()),
    (0x0010, "INT24", Kind.SIGNED, 24, ("INTEGER24",)),
    (0x0011, "LREAL", Kind.REAL, 64, ("REAL64", "DOUBLE")),
    (0x0012, "INT40", Kind.SIGNED, 40, ("INTEGER40",)),
    (0x0013, "INT48", Kind.SIGNED, 48, ("INTEGER48",)),
    (0x0014, "INT56", Kind.SIGNED, 56, ("INTEGER56",)),
    (0x0015, "LINT", Kind.SIGNED, 64, ("INTEGER64", "INT64")),
    (0x0016, "UINT24", Kind.UNSIGNED, 24, ("UNSIGNED24",)),
    (0x0018, "UINT40", Kind.UNSIGNED, 40, ("UNSIGNED40",)),
    (0x0019, "UINT48", Kind.UNSIGNED, 48, ("UNSIGNED48",)),
    (0x001A, "UINT56", Kind.UNSIGNED, 56, ("UNSIGNED56",)),
    (0x001B, "ULINT", Kind.UNSIGNED, 64, ("UNSIGNED64", "UINT64")),
    (0x001D, "GUID", Kind.OCTETS, 128, ()),
    (0x001E, "BYTE", Kind.BITS, 8, ()),
    (0x001F, "WORD", Kind.BITS, 16, ()),
    (0x0020, "DWORD", Kind.BITS, 32, ()),
    (0x002D, "BITARR8", Kind.BITS, 8, ()),
    (0x002E, "BITARR16", Kind.BITS, 16, ()),
    (0x002F, "BITARR32", Kind.BITS, 32, ()),
] + [(0x0030 + i - 1, f"BIT{i}", Kind.BITS, i, ()) for i in range(1, 9)]

BY_CODE: dict[int, DataType] = {}
BY_NAME: dict[str, DataType] = {}
for _code, _name, _kind, _bits, _aliases in _STANDARD:
    _dt = DataType(_code, _name, _kind, _bits)
    BY_CODE[_code] = _dt
    for _n in (_name, *_aliases):
        BY_NAME[_n.upper()] = _dt
# BIT1 is a BOOL-sized bit field; keep BOOL as the code-1 type but let "BIT1" resolve to 0x30.

_STRING_N = re.compile(r"^(STRING|VISIBLE_STRING|OCTET_STRING|UNICODE_STRING|WSTRING)\s*\(\s*(\d+)\s*\)$")
_ARRAY = re.compile(r"^ARRAY\s*\[\s*(\d+)\s*\.\.\s*(\d+)\s*\]\s*OF\s+(.+)$")


def lookup(name_or_code: str | int) -> DataType | None:
    """Resolve a standard type by code or by any of its names (case-insensitive).

    ``STRING(8)`` resolves to STRING with 64 bits. Returns None for unknown (vendor) names; the ESI
    reader resolves those through the file's own ``DataTypes``.
    """
    if isinstance(name_or_code, int):
        return BY_CODE.get(name_or_code)
    key = name_or_code.strip().upper()
    dt = BY_NAME.get(key)
    if dt is not None:
        return dt
    m = _STRING_N.match(key)
    if m:
        base = BY_NAME[m.group(1)]
        n = int(m.group(2))
        return DataType(base.code, f"{base.name}({n})", base.kind, n * (16 if base.kind is Kind.UNICODE else 8))
    return None


def parse_array_name(name: str) -> tuple[int, int, str] | None:
    """``ARRAY [0..3] OF UINT`` → (0, 3, "UINT")."""
    m = _ARRAY.match(name.strip().upper())
    if not m:
        return None
    return int(m.group(1)), int(m.group(2)), m.group(3).strip()


def require(name_or_code: str | int) -> DataType:
    dt = lookup(name_or_code)
    if dt is None:
        raise EncodeError(f"unknown data type {name_or_code!r}")
    return dt


def for_size(bits: int, signed: bool = False) -> DataType:
    """The standard integer type of exactly ``bits`` bits (8/16/24/32/40/48/56/64)."""
    for dt in BY_CODE.values():
        if dt.bits == bits and dt.kind is (Kind.SIGNED if signed else Kind.UNSIGNED):
            return dt
    raise EncodeError(f"no {'signed' if signed else 'unsigned'} integer type of {bits} bits")


BOOL = BY_CODE[0x01]
SINT = BY_CODE[0x02]
INT = BY_CODE[0x03]
DINT = BY_CODE[0x04]
USINT = BY_CODE[0x05]
UINT = BY_CODE[0x06]
UDINT = BY_CODE[0x07]
REAL = BY_CODE[0x08]
STRING = BY_CODE[0x09]
OCTET_STRING = BY_CODE[0x0A]
LREAL = BY_CODE[0x11]
LINT = BY_CODE[0x15]
ULINT = BY_CODE[0x1B]
