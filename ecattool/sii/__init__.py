"""SII EEPROM images: parse (binary or Intel HEX), serialize, CRC, check, diff, build from an ESI device."""

from ecattool.sii.builder import assemble, build
from ecattool.sii.checks import check, check_against, check_file, fix_crc, set_alias
from ecattool.sii.crc import crc8, preamble_crc
from ecattool.sii.compare import Difference, diff, flatten
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
    "assemble", "build", "check", "check_against", "check_file", "fix_crc", "set_alias", "Difference", "diff",
    "flatten",
    "Category", "CategoryType", "DcCategory", "FmmuCategory", "GeneralCategory", "PdoCategory", "RawCategory",
    "SiiDcOpMode", "SiiHeader", "SiiImage", "SiiPdo", "SiiPdoEntry", "SiiSyncManager", "StringsCategory",
    "SyncMCategory", "category_name", "crc8", "load", "parse", "preamble_crc", "serialize", "write_intel_hex",
]
