"""The one exception hierarchy of ecattool.

Every error a user can cause by giving bad input is an :class:`EcatToolError` that carries a
:class:`Location` (file, line, column where known). The CLI prints ``str(error)`` as a single line and exits
with status 1; library users catch :class:`EcatToolError`.
"""

from __future__ import annotations

from collections.abc import Iterable

from ecattool.abort import abort_text, al_status_text
from ecattool.record import FrozenRecord, set_field


def did_you_mean(word: str, choices: Iterable[str]) -> str:
    """`` (did you mean 'x'?)`` naming the nearest of ``choices`` to a misspelled ``word``; "" when none is near."""
    import difflib  # on first use: reading a file never needs it (~1.5 ms of every process's start)

    near = difflib.get_close_matches(word, sorted(choices), n=1, cutoff=0.6)
    return f" (did you mean {near[0]!r}?)" if near else ""


class Location(FrozenRecord):
    """Where something came from: a file and, where known, a 1-based line and column."""

    __slots__ = ("file", "line", "column")
    file: str | None
    line: int | None
    column: int | None

    def __init__(self, file: str | None = None, line: int | None = None, column: int | None = None) -> None:
        set_field(self, "file", file)
        set_field(self, "line", line)
        set_field(self, "column", column)

    def __str__(self) -> str:
        parts = [self.file or "<input>"]
        if self.line is not None:
            parts.append(str(self.line))
            if self.column is not None:
                parts.append(str(self.column))
        return ":".join(parts)

    def with_line(self, line: int | None, column: int | None = None) -> "Location":
        return Location(self.file, line, column)


class EcatToolError(Exception):
    """Base class of every error ecattool raises on purpose."""

    def __init__(self, message: str, location: Location | None = None) -> None:
        super().__init__(message)
        self.message = message
        self.location = location

    def __str__(self) -> str:
        if self.location is None:
            return self.message
        return f"{self.location}: {self.message}"


class InputError(EcatToolError):
    """A file or value given by the user is malformed or inconsistent."""


class XmlSecurityError(InputError):
    """An XML document uses a feature ecattool refuses (DTD entities, external references, excess size)."""


class SelectionError(EcatToolError):
    """A device, profile or object selector matched nothing (or was ambiguous)."""


class EncodeError(InputError):
    """A value cannot be encoded as the requested CoE data type (range, type)."""


class TargetError(EcatToolError):
    """A target (simulator or real master) refused or failed a request."""


class SdoAbort(TargetError):
    """An SDO transfer ended with a CiA-301 abort code."""

    def __init__(self, index: int, subindex: int, code: int, message: str | None = None) -> None:
        self.index = index
        self.subindex = subindex
        self.code = code
        text = message or abort_text(code)
        super().__init__(f"SDO abort 0x{code:08X} on 0x{index:04X}:{subindex:02X}: {text}")


class SdoTimeout(TargetError):
    """An SDO request got no reply in time."""

    def __init__(self, index: int, subindex: int, position: int | None = None, name: str = "",
                 detail: str = "no reply") -> None:
        self.index = index
        self.subindex = subindex
        self.position = position
        self.name = name
        of = "" if position is None else f" of slave {position}" + (f" ({name})" if name else "")
        super().__init__(f"SDO timeout on 0x{index:04X}:{subindex:02X}{of}: {detail}")


class SdoTooLarge(TargetError):
    """A slave answered an SDO upload with more octets than the object can have (its type's size, or the
    documented bound where the type is not known): the reply is refused, never copied on."""

    def __init__(self, index: int, subindex: int, position: int | None, size: int, got: int | None = None,
                 known: bool = True) -> None:
        self.index = index
        self.subindex = subindex
        self.position = position
        self.size = size
        self.got = got
        of = "" if position is None else f"slave {position}: "
        said = "the slave announced more than" if got is None else f"the reply has {got} octets, more than"
        bound = (f"the {size} the object can have" if known else
                 f"the {size} octets read of an object whose type is not known")
        super().__init__(f"{of}0x{index:04X}:{subindex:02X}: {said} {bound} (refused)")


class StateChangeError(TargetError):
    """An EtherCAT state change was refused; ``al_status`` holds the AL status code."""

    def __init__(self, requested: str, current: str, al_status: int, message: str | None = None) -> None:
        self.requested = requested
        self.current = current
        self.al_status = al_status
        text = message or al_status_text(al_status)
        super().__init__(
            f"state change {current} -> {requested} refused with AL status 0x{al_status:04X}: {text}"
        )
