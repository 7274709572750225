"""Small helpers the format modules share: hex data, comments, type names by size, C/Python names."""

from __future__ import annotations

import re
from typing import Any

from ecattool.errors import InputError, Location
from ecattool.startup.config import SlaveConfig
from ecattool.startup.model import TRANSITIONS

#: unsigned type names by byte size, for commands that carry no type
_UNSIGNED_BY_SIZE = {1: "USINT", 2: "UINT", 4: "UDINT", 8: "ULINT"}


def unsigned_type(size: int) -> str | None:
    return _UNSIGNED_BY_SIZE.get(size)



def parse_hex(text: str, location: Location | None, what: str = "data") -> bytes:
    """Hex bytes as written by TwinCAT/lcec/ecattool: ``0116``, ``01 16``, ``0x01 0x16``."""
    s = re.sub(r"0x", "", (text or "").strip(), flags=re.IGNORECASE).replace(" ", "").replace(",", "")
    try:
        return bytes.fromhex(s)
    except ValueError:
        raise InputError(f"{what} {text!r} is not hex bytes (write e.g. 0116 or '01 16')", location) from None


def one_line(text: str) -> str:
    """Comments in line-based formats: no line breaks, trimmed."""
    return " ".join((text or "").split())


def check_transition(text: str, location: Location | None) -> str:
    t = (text or "").strip().upper()
    if t not in TRANSITIONS:
        raise InputError(f"unknown transition {text!r} (expected one of {', '.join(TRANSITIONS)})", location)
    return t


def int_in_range(value: int, bits: int, location: Location | None, what: str) -> int:
    if not 0 <= value < (1 << bits):
        raise InputError(f"{what} {value} is out of range (0..0x{(1 << bits) - 1:X})", location)
    return value


def encode_sized(value: int, size: int, location: Location | None, what: str = "value") -> bytes:
    """An integer written with an explicit byte size (ecmc, TwinCAT): negative values in two's complement."""
    if size <= 0 or size > 8:
        raise InputError(f"byte size {size} is not 1..8", location)
    if -(1 << (8 * size - 1)) <= value < 0:
        value += 1 << (8 * size)
    if not 0 <= value < (1 << (8 * size)):
        raise InputError(f"{what} {value} does not fit in {size} byte(s)", location)
    return value.to_bytes(size, "little")


def identifier(text: str, default: str = "slave") -> str:
    """A C/Python identifier made from a slave name."""
    s = re.sub(r"[^0-9A-Za-z_]+", "_", text or "").strip("_").lower()
    if not s:
        s = default
    if s[0].isdigit():
        s = f"{default}_{s}"
    return s


def unique_identifiers(configs: list[SlaveConfig]) -> list[str]:
    seen: dict[str, int] = {}
    out = []
    for i, c in enumerate(configs):
        base = identifier(c.name or (f"slave{c.position}" if c.position is not None else f"slave{i}"))
        n = seen.get(base, 0)
        seen[base] = n + 1
        out.append(base if n == 0 else f"{base}_{n + 1}")
    return out




def decode_text(data: bytes, source: str) -> str:
    """UTF-8 text (a BOM allowed); invalid bytes are an error naming the line."""
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        line = data.count(b"\n", 0, exc.start) + 1
        raise InputError(f"not UTF-8 text (byte 0x{data[exc.start]:02X})", Location(source, line)) from None


def as_list(value: object, location: Location | None, what: str) -> list[Any]:
    """A YAML/JSON value that must be a list (None = empty)."""
    if value is None:
        return []
    if not isinstance(value, list):
        raise InputError(f"{what} must be a list, got {type(value).__name__}", location)
    return value


def check_commands(configs: list[SlaveConfig]) -> None:
    """Index, sub-index and data of every command are within CoE limits (whatever format they came from)."""
    for c in configs:
        for cmd in c.commands:
            if not 0 <= cmd.index <= 0xFFFF or not 0 <= cmd.subindex <= 0xFF:
                raise InputError(f"object 0x{cmd.index:X}:{cmd.subindex:X} is out of range (index 0..0xFFFF, "
                                 "sub-index 0..0xFF)", cmd.source)
            if not cmd.data:
                raise InputError(f"{cmd.address}: a startup download needs at least one data byte", cmd.source)
        for s in c.soe_commands:
            if not 0 <= s.idn <= 0xFFFF or not 0 <= s.drive_no <= 7:
                raise InputError(f"SoE IDN {s.idn} drive {s.drive_no} is out of range", s.source)
