"""Object values as people read them: decoded by data type, integers in decimal and hex, the bits of the
CiA-402 controlword and statusword by name. For tables and transcripts; ``--json`` keeps the raw form."""

from __future__ import annotations

from ecattool.od.types import DataType, Kind

#: CiA-402 controlword (6040h) bits that are the same in every mode (bits 4-6 and 9 depend on the mode)
CONTROLWORD_BITS = {0: "switch on", 1: "enable voltage", 2: "quick stop", 3: "enable operation",
                    7: "fault reset", 8: "halt"}
#: CiA-402 statusword (6041h) bits (12, 13 depend on the mode; 8, 14, 15 are the manufacturer's)
STATUSWORD_BITS = {0: "ready to switch on", 1: "switched on", 2: "operation enabled", 3: "fault",
                   4: "voltage enabled", 5: "quick stop", 6: "switch on disabled", 7: "warning", 9: "remote",
                   10: "target reached", 11: "internal limit active"}
_WORD_BITS = {0x6040: CONTROLWORD_BITS, 0x6041: STATUSWORD_BITS}


def bit_names(index: int, value: int) -> list[str]:
    """The named bits set in a controlword (6040h) or statusword (6041h) value; [] for other objects."""
    names = _WORD_BITS.get(index)
    if names is None:
        return []
    return [names.get(bit, f"bit {bit}") for bit in range(16) if value >> bit & 1]


def int_text(value: int, size: int, index: int | None = None, unit: str = "") -> str:
    """``2000 (0x000007D0)``, ``2000 mm (0x000007D0)`` with a unit; a negative value with its two's complement
    (``-5 (0xFFFB)``); the set bits named for the controlword and statusword."""
    size = max(1, size)
    text = f"{value}{' ' + unit if unit else ''} (0x{value & ((1 << (8 * size)) - 1):0{2 * size}X})"
    named = bit_names(index, value) if index is not None else []
    return f"{text}: {', '.join(named)}" if named else text


def value_text(data: bytes, datatype: DataType | None = None, bits: int | None = None, index: int | None = None,
               unit: str = "") -> str:
    """``data`` (little-endian, as on the wire or in an ESI ``DefaultData``) decoded by ``datatype``: numbers in
    decimal and hex with ``unit``, text quoted, other bytes as spaced hex. Without a data type, 1, 2, 4 or 8
    bytes read as an unsigned integer."""
    suffix = f" {unit}" if unit else ""
    if datatype is None or datatype.kind in (Kind.UNSIGNED, Kind.SIGNED, Kind.BITS, Kind.BOOL):
        if (datatype is None and len(data) in (1, 2, 4, 8)) or (datatype is not None and 0 < len(data) <= 8):
            try:
                value = datatype.decode(data, bits) if datatype is not None else int.from_bytes(data, "little")
            except Exception:  # a size that does not fit the type (a vendor file's slip): show the bytes
                value = None
            if isinstance(value, int):
                return int_text(value, len(data), index, unit)
    elif datatype.kind is Kind.REAL:
        try:
            return f"{datatype.decode(data, bits):.7g}{suffix}"
        except Exception:
            pass
    elif datatype.kind in (Kind.STRING, Kind.UNICODE):
        try:
            return repr(datatype.decode(data, bits))
        except Exception:
            pass
    return data.hex(" ") if data else "(empty)"
