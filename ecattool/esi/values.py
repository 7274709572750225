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
        """HexDecValue: ``#x1A00`` or decimal (``-5`` allowed); ``0x1A00`` is tolerated with a warning."""
        if text is None:
            raise InputError(f"{what} is missing (expected #x… hex or decimal)", self.loc(el))
        s = text.strip()
        try:
            head = s[:2]
            if head == "#x" or head == "#X":
                if s[2:4] in ("0x", "0X"):
                    self.warn("esi-number-0x", f"{what} {s!r} has both #x and 0x prefixes (read as hex)", el)
                return int(s[2:], 16)
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


def lc_text(parent: Any, tag: str) -> str:
    """Text of the ``tag`` child with LcId 1033 (English), else the first one; '' when absent."""
    first = None
    for el in parent.iterchildren(tag):
        if first is None:
            first = el
        if (el.get("LcId") or "").strip() == "1033":
            return (el.text or "").strip()
    return (first.text or "").strip() if first is not None else ""


def name_step(c: Any, name: str | None, final: bool) -> tuple[str | None, bool]:
    """One ``Name`` element seen, by the rule of :func:`lc_text` (LcId 1033, else the first): (name, final)."""
    if final:
        return name, True
    lcid = c.get("LcId")
    if lcid is not None and lcid.strip() == "1033":
        return (c.text or "").strip(), True
    if name is None:
        return (c.text or "").strip(), False
    return name, False


__all__ = ["Context", "fast_number", "lc_text", "name_step"]
