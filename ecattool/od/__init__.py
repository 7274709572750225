"""CoE data types and the object dictionary model (the shared core of ecattool)."""

from ecattool.abort import abort_text, al_status_text
from ecattool.od.model import (
    RO,
    RW,
    WO,
    Access,
    EcState,
    Entry,
    ObjectCode,
    ObjectDictionary,
    OdObject,
    normalize_name,
)
from ecattool.od.numbers import format_address, parse_address, parse_int
from ecattool.od.types import DataType, Kind, lookup, require

__all__ = [
    "RO", "RW", "WO", "Access", "DataType", "EcState", "Entry", "Kind", "ObjectCode", "ObjectDictionary",
    "OdObject", "abort_text", "al_status_text", "format_address", "lookup", "normalize_name", "parse_address",
    "parse_int", "require",
]
