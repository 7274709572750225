"""EasyMotion Studio / EasySetUp ``parameters.cfg``: names, types and addresses of the setup variables.

One parameter per line, tab-separated: ``TYPE  Name  [unit]  @0xADDR  =value(0xHEX)  >min  <max  %step``
(unit, limits and step optional; floating-point parameters have no hex form). The file is ISO-8859-1.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

from ecattool.errors import InputError, Location

#: size in 16-bit words of each parameter type
TYPE_WORDS = {"INT": 1, "UINT": 1, "LONG": 2, "ULONG": 2, "FIXED": 2, "FLOAT": 2, "DOUBLE": 4}
INTEGER_TYPES = ("INT", "UINT", "LONG", "ULONG", "FIXED")

_HEX = re.compile(r"\(0x([0-9A-Fa-f]+)\)")


@dataclass(frozen=True, slots=True)
class Parameter:
    name: str
    type: str
    address: int
    unit: str = ""
    value_text: str = ""  # what the file prints after '=' (display units for FLOAT/DOUBLE)
    raw: int | None = None  # the hex value printed in parentheses, when there is one
    location: Location | None = None

    @property
    def words(self) -> int:
        return TYPE_WORDS[self.type]


@dataclass(frozen=True, slots=True)
class ParameterTable:
    parameters: tuple[Parameter, ...]
    source: str | None = None

    def by_name(self, name: str) -> Parameter | None:
        for p in self.parameters:
            if p.name == name:
                return p
        lowered = [p for p in self.parameters if p.name.lower() == name.lower()]
        return lowered[0] if len(lowered) == 1 else None

    def by_address(self, address: int) -> Parameter | None:
        for p in self.parameters:
            if p.address == address:
                return p
        return None


def parse_parameters(data: bytes | str, source: str | None = None) -> ParameterTable:
    text = data.decode("latin-1") if isinstance(data, bytes) else data
    params: list[Parameter] = []
    seen: dict[int, int] = {}
    for no, raw in enumerate(text.splitlines(), 1):
        line = raw.strip()
        if not line:
            continue
        fields = [f for f in raw.strip("\r\n").split("\t") if f != ""]
        loc = Location(source, no)
        if len(fields) < 3:
            raise InputError(f"expected 'TYPE<tab>Name<tab>@0xADDR<tab>=value', got {line[:40]!r}", loc)
        ptype, name = fields[0].strip(), fields[1].strip()
        if ptype not in TYPE_WORDS:
            raise InputError(f"unknown parameter type {ptype!r} (known: {', '.join(TYPE_WORDS)})", loc)
        at = [f for f in fields[2:] if f.startswith("@")]
        if not at:
            raise InputError(f"parameter {name} has no '@0xADDR' field", loc)
        try:
            address = int(at[0][1:], 16)
        except ValueError:
            raise InputError(f"parameter {name}: {at[0]!r} is not an address like @0x0252", loc) from None
        if not 0 <= address <= 0xFFFF:
            raise InputError(f"parameter {name}: address {at[0]} is not a 16-bit address", loc)
        if address in seen:
            raise InputError(f"parameter {name} uses address 0x{address:04X} again (first at line {seen[address]})", loc)
        seen[address] = no
        unit = next((f.strip()[1:-1] for f in fields[2:] if f.strip().startswith("[") and f.strip().endswith("]")), "")
        value = next((f[1:] for f in fields[2:] if f.startswith("=")), "")
        m = _HEX.search(value)
        params.append(Parameter(name, ptype, address, unit, value, int(m.group(1), 16) if m else None, loc))
    return ParameterTable(tuple(params), source)


def read_parameters(path: str | Path) -> ParameterTable:
    from ecattool.fileio import read_bytes

    return parse_parameters(read_bytes(path, 8 * 1024 * 1024), str(path))
