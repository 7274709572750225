"""SII EEPROM images: parse (binary or Intel HEX), serialize, CRC, check, diff, build from an ESI device.

The names below are imported from their submodules on first use, so ``sii build`` does not pay for the
checks, the comparison or the formatting it does not run.
"""

from __future__ import annotations

import importlib
from typing import Any

_WHERE = {
    "ecattool.sii.builder": ("assemble", "build"),
    "ecattool.sii.checks": ("check", "check_against", "check_file", "set_alias"),
    "ecattool.sii.crc": ("crc8", "preamble_crc"),
    "ecattool.sii.compare": ("Difference", "diff", "flatten"),
    "ecattool.sii.image": ("load", "parse", "write_intel_hex"),
    "ecattool.sii.model": ("Category", "CategoryType", "DcCategory", "FmmuCategory", "GeneralCategory",
                           "PdoCategory", "RawCategory", "SiiDcOpMode", "SiiHeader", "SiiImage", "SiiPdo",
                           "SiiPdoEntry", "SiiSyncManager", "StringsCategory", "SyncMCategory", "category_name",
                           "fix_crc", "serialize"),
}
_MODULE_OF = {name: module for module, names in _WHERE.items() for name in names}


def __getattr__(name: str) -> Any:
    module = _MODULE_OF.get(name)
    if module is None:
        raise AttributeError(f"module 'ecattool.sii' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted([*globals(), *_MODULE_OF])


__all__ = [
    "Category", "CategoryType", "DcCategory", "Difference", "FmmuCategory", "GeneralCategory", "PdoCategory",
    "RawCategory", "SiiDcOpMode", "SiiHeader", "SiiImage", "SiiPdo", "SiiPdoEntry", "SiiSyncManager",
    "StringsCategory", "SyncMCategory", "assemble", "build", "category_name", "check", "check_against",
    "check_file", "crc8", "diff", "fix_crc", "flatten", "load", "parse", "preamble_crc", "serialize",
    "set_alias", "write_intel_hex",
]
