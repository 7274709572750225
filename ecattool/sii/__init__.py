"""SII EEPROM images: parse (binary or Intel HEX), serialize, CRC, check, diff, build from an ESI device."""

from ecattool.sii.crc import crc8, preamble_crc
from ecattool.sii.image import load, parse, serialize, write_intel_hex
from ecattool.sii.model import (
    Category,
    CategoryType,
    DcCategory,
    FmmuCategory,
    GeneralCategory,
    PdoCategory,
    RawCategory,
    SiiDcOpMode,
    SiiHeader,
    SiiImage,
    SiiPdo,
    SiiPdoEntry,
    SiiSyncManager,
    StringsCategory,
    SyncMCategory,
    category_name,
)

__all__ = [
    "Category", "CategoryType", "DcCategory", "FmmuCategory", "GeneralCategory", "PdoCategory", "RawCategory",
    "SiiDcOpMode", "SiiHeader", "SiiImage", "SiiPdo", "SiiPdoEntry", "SiiSyncManager", "StringsCategory",
    "SyncMCategory", "category_name", "crc8", "load", "parse", "preamble_crc", "serialize", "write_intel_hex",
]
