"""Findings: what every check in ecattool reports (rule id, severity, message, location).

Checks in ``esi``, ``pdo``, ``scaling``, ``sw``, ``sii`` and ``project`` return lists of :class:`Finding`;
``project.lint`` gathers them and the CLI renders them as text, JSON, SARIF or GitHub annotations.
"""

from __future__ import annotations

from collections.abc import Sequence
from enum import Enum
from typing import Any

from ecattool.errors import Location
from ecattool.record import FrozenRecord, set_field


class Severity(str, Enum):
    ERROR = "error"
    WARNING = "warning"
    INFO = "info"

    @property
    def rank(self) -> int:
        return {"error": 2, "warning": 1, "info": 0}[self.value]


class Finding(FrozenRecord):
    __slots__ = ("rule", "severity", "message", "location", "data")
    rule: str
    severity: Severity
    message: str
    location: Location | None
    data: dict[str, Any]

    def __init__(self, rule: str, severity: Severity, message: str, location: Location | None = None,
                 data: dict[str, Any] | None = None) -> None:
        set_field(self, "rule", rule)
        set_field(self, "severity", severity)
        set_field(self, "message", message)
        set_field(self, "location", location)
        set_field(self, "data", {} if data is None else data)

    def __str__(self) -> str:
        where = f"{self.location}: " if self.location else ""
        return f"{where}{self.severity.value}: {self.message} [{self.rule}]"

    def to_json(self) -> dict[str, Any]:
        loc = self.location
        return {
            "rule": self.rule,
            "severity": self.severity.value,
            "message": self.message,
            "file": loc.file if loc else None,
            "line": loc.line if loc else None,
            "column": loc.column if loc else None,
            **({"data": self.data} if self.data else {}),
        }


def has_errors(findings: Sequence[Finding], strict: bool = False) -> bool:
    """True when any finding fails a check (errors; warnings too when ``strict``)."""
    threshold = Severity.WARNING.rank if strict else Severity.ERROR.rank
    return any(f.severity.rank >= threshold for f in findings)
