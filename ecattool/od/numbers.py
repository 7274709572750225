"""Parsing the numbers and object addresses engineers type: ``0x1C12``, ``#x1C12``, ``7186``, ``6060:00``."""

from __future__ import annotations

import re
from typing import TYPE_CHECKING

from ecattool.errors import InputError, Location

if TYPE_CHECKING:
    from fractions import Fraction

_ADDR = re.compile(r"^\s*(?:0x|#x)?([0-9A-Fa-f]{1,4})(?:h)?\s*[:.]\s*(?:0x|#x)?([0-9A-Fa-f]{1,2})(?:h)?\s*$")


def parse_int(text: str | int, location: Location | None = None, what: str = "number") -> int:
    """``0x1C12``, ``#x1C12``, ``1C12h``, ``-5``, ``7186`` → int. Raises :class:`InputError`."""
    if isinstance(text, bool):  # YAML true/false: a boolean is never a number
        raise InputError(f"{what} must be a number, not {str(text).lower()}", location)
    if isinstance(text, int):
        return text
    s = str(text).strip().replace("_", "")
    neg = s.startswith("-")
    body = s[1:] if neg else s
    try:
        if body[:2].lower() in ("0x", "#x"):
            v = int(body[2:], 16)
        elif body[-1:].lower() == "h" and len(body) > 1:
            v = int(body[:-1], 16)
        elif body[:2].lower() == "0b":
            v = int(body[2:], 2)
        else:
            v = int(body, 10)
    except (ValueError, IndexError):
        raise InputError(f"{text!r} is not a valid {what} (use 0x1C12, #x1C12 or decimal)", location) from None
    return -v if neg else v


#: The largest decimal exponent an exact number may be written with: ``1e999`` is a typo, and ``Fraction("1e99999999")``
#: would compute a 100-million-digit integer for minutes (issue 28.2: bounded work for any input).
MAX_EXPONENT = 30

_EXPONENT = re.compile(r"[eE]\s*([-+]?\d+)")


def check_exponent(text: object, location: Location | None = None, what: str = "number") -> None:
    """Refuse a number written with a decimal exponent beyond :data:`MAX_EXPONENT` (``5e999 mm`` too), before
    anything makes it exact."""
    if isinstance(text, str):
        for m in _EXPONENT.finditer(text):
            if abs(int(m.group(1)[:6])) > MAX_EXPONENT:
                raise InputError(f"{what} {text[:40]!r} is out of range (exponent beyond ±{MAX_EXPONENT})", location)


def parse_fraction(text: object, location: Location | None = None, what: str = "number") -> Fraction:
    """``12.5``, ``1/3``, ``2.5e-3``, an int or a Fraction → an exact :class:`~fractions.Fraction`; a boolean, a
    non-finite float, a huge exponent or anything else is an :class:`InputError`."""
    from fractions import Fraction  # on first use: fractions (and decimal) cost ~4 ms of every process's start

    if isinstance(text, bool):
        raise InputError(f"{what} must be a number, not {str(text).lower()}", location)
    if isinstance(text, (int, Fraction)):
        return Fraction(text)
    check_exponent(str(text), location, what)
    try:
        return Fraction(str(text).strip())
    except (ValueError, ZeroDivisionError, OverflowError, TypeError):
        raise InputError(f"{what} {str(text)[:40]!r} is not a number", location) from None


def parse_address(text: str, location: Location | None = None) -> tuple[int, int]:
    """``6060:00``, ``0x6060:0``, ``#x6060:0``, ``6060h:00h`` → (index, subindex), both hexadecimal.

    A bare index (``0x6060``) means sub-index 0.
    """
    m = _ADDR.match(str(text))
    if m:
        return int(m.group(1), 16), int(m.group(2), 16)
    s = str(text).strip()
    if ":" not in s:
        idx = parse_int(s if s[:2].lower() in ("0x", "#x") or s.endswith(("h", "H")) else "0x" + s, location, "object index")
        if 0 <= idx <= 0xFFFF:
            return idx, 0
    raise InputError(f"{text!r} is not an object address (write 6060:00 or 0x6060:0)", location)


def format_address(index: int, subindex: int) -> str:
    return f"0x{index:04X}:{subindex:02X}"
