"""Scalar values as ESI files write them: HexDecValue numbers, booleans, hex binary, LcId-tagged names.

Every function takes the element the text came from, so that errors and warnings carry file and line.
"""

from __future__ import annotations

from typing import Any

from ecattool.errors import InputError, Location
from ecattool.findings import Finding, Severity
from ecattool.record import Record

_TRUE = frozenset({"1", "true"})
_FALSE = frozenset({"0", "false"})


class Context(Record):
    """Per-file reading state: the source name (for locations) and the collected warnings."""

    __slots__ = ("source", "warnings")
    source: str
    warnings: list[Finding]

    def __init__(self, source: str, warnings: list[Finding] | None = None) -> None:
        self.source = source
        self.warnings = [] if warnings is None else warnings

    def loc(self, el: Any) -> Location:
        return Location(self.source, getattr(el, "sourceline", None))

    def warn(self, rule: str, message: str, el: Any = None, **data: Any) -> None:
        self.warnings.append(Finding(rule, Severity.WARNING, message, self.loc(el) if el is not None else Location(self.source), data))

    # --- numbers -----------------------------------------------------------------------------
    def number(self, text: str | None, el: Any, what: str) -> int:
        """HexDecValue (``#x1A00``, or decimal with an optional sign) and xs:int/xs:integer (decimal, surrounding
        blanks allowed); ``0x1A00`` is tolerated with a warning.

        The schema's hex pattern is ``#x[0-9|a-f|A-F]{1,}``: inside a character class ``|`` is a literal, so
        ``#x1|2`` is schema-valid; such a value is read without the bars, with a warning ``esi-number-bar``.
        """
        if text is None:
            raise InputError(f"{what} is missing (expected #x… hex or decimal)", self.loc(el))
        s = text.strip()
        try:
            head = s[:2]
            if head == "#x" or head == "#X":
                if s[2:4] in ("0x", "0X"):
                    self.warn("esi-number-0x", f"{what} {s!r} has both #x and 0x prefixes (read as hex)", el)
                digits = s[2:]
                if "|" in digits and digits.replace("|", ""):
                    self.warn("esi-number-bar", f"{what} {s!r} has '|' among its hex digits (the schema's pattern "
                              "allows it); read without it", el)
                    digits = digits.replace("|", "")
                return int(digits, 16)
            if head == "0x" or head == "0X":
                self.warn("esi-number-0x", f"{what} {s!r} uses 0x; ESI HexDecValue is #x… (read as hex)", el)
                return int(s[2:], 16)
            if s.isdigit():
                return int(s)
            return int(s, 10)
        except ValueError:
            raise InputError(f"{what} {s!r} is not a number (expected #x… hex or decimal)", self.loc(el)) from None

    def opt_number(self, text: str | None, el: Any, what: str) -> int | None:
        if text is None or not text.strip():
            return None
        return self.number(text, el, what)

    def unsigned(self, text: str | None, el: Any, what: str, bits: int) -> int | None:
        """An optional HexDecValue that fills a ``bits``-wide register field (an SM's control or enable byte).

        The schema allows any integer there; a value outside ``0 … 2**bits-1`` is kept to its low ``bits`` bits
        (two's complement for a negative one) with a warning ``esi-number-range``."""
        if text is None or not text.strip():
            return None
        v = self.number(text, el, what)
        if 0 <= v < 1 << bits:
            return v
        masked = v & ((1 << bits) - 1)
        self.warn("esi-number-range", f"{what} {text.strip()!r} does not fit {bits} bits; read as {masked:#x}", el)
        return masked

    def flag(self, text: str | None, el: Any, what: str) -> bool:
        """A HexDecValue that the schema uses as a yes/no mark (``Slot/ModuleIdent@Default``): non-zero is yes.

        ``true``/``false`` (not schema-valid there, but written by tools) are read as booleans."""
        if text is None:
            return False
        t = text.strip().lower()
        if t in _TRUE or t in _FALSE:
            return t in _TRUE
        return self.number(text, el, what) != 0

    def boolean(self, text: str | None, el: Any, what: str, default: bool = False) -> bool:
        if text is None:
            return default
        t = text.strip().lower()
        if t in _TRUE:
            return True
        if t in _FALSE:
            return False
        if not t:
            self.warn("esi-boolean-empty", f"{what} is empty; read as {str(default).lower()}", el)
            return default
        raise InputError(f"{what} {text.strip()!r} is not a boolean (expected 0, 1, true or false)", self.loc(el))

    def hexbin(self, text: str | None, el: Any, what: str) -> bytes:
        """xs:hexBinary; an odd number of digits is read with a leading 0 and a warning."""
        if text is not None and not len(text) & 1:
            try:
                return bytes.fromhex(text)
            except ValueError:
                pass
        s = "".join((text or "").split())
        if s[:2] in ("#x", "0x"):
            s = s[2:]
        if len(s) % 2:
            self.warn("esi-hex-odd", f"{what} {s!r} has an odd number of hex digits; read as '0{s}'", el)
            s = "0" + s
        try:
            return bytes.fromhex(s)
        except ValueError:
            raise InputError(f"{what} {s[:40]!r} is not hex binary data", self.loc(el)) from None


def fast_number(t: str | None) -> int | None:
    """The common HexDecValue spellings without any checks; None sends the text to :meth:`Context.number`."""
    if t is None or not t.isascii():
        return None
    if t.isdigit():
        return int(t)
    if t[:2] == "#x" and t[2:].isalnum() and "x" not in t[2:] and "X" not in t[2:]:
        try:
            return int(t[2:], 16)
        except ValueError:
            return None
    return None


#: :func:`lang_rank` of nothing seen yet (worse than any element)
NO_NAME = 3


def lang_rank(lcid: str | None) -> int:
    """How well an element with this ``LcId`` gives the English text ecattool shows (the one rule for every
    language-tagged ESI element: Name, Desc, Text, Comment, URL): 0 for 1033 (English, United States); 1 for
    another English (primary language 09h of the Windows LCID: 2057 en-GB, 3081 en-AU, 4105 en-CA…); 2 for any
    other language or none. The best rank wins, the first element among equals. ``LcId`` is xs:integer: a sign,
    leading zeros and blanks are allowed."""
    if lcid == "1033":
        return 0
    if lcid is None or lcid == "1031":  # the two spellings almost every file uses, without parsing
        return 2
    t = lcid.strip().lstrip("+")
    if not t.isdigit():
        return 2
    n = int(t)
    return 0 if n == 1033 else 1 if n & 0x3FF == 0x09 else 2


def is_english(lcid: str | None) -> bool:
    """``LcId`` is 1033, English (United States)."""
    return lang_rank(lcid) == 0


def name_step(c: Any, name: str | None, rank: int) -> tuple[str | None, int]:
    """One language-tagged element ``c`` seen after the best so far (``name`` of ``rank``; start with None and
    :data:`NO_NAME`): the new best by :func:`lang_rank` (stop at rank 0)."""
    if rank == 0:
        return name, 0
    r = lang_rank(c.get("LcId"))
    if r < rank:
        return (c.text or "").strip(), r
    return name, rank


def lc_text(parent: Any, tag: str) -> str:
    """Text of the ``tag`` child in English by :func:`lang_rank` (1033, else another English, else the first);
    '' when absent."""
    name: str | None = None
    rank = NO_NAME
    for el in parent.iterchildren(tag):
        name, rank = name_step(el, name, rank)
        if rank == 0:
            break
    return name or ""


__all__ = ["NO_NAME", "Context", "fast_number", "is_english", "lang_rank", "lc_text", "name_step"]
