"""Lint: the findings of the machine a project sets up (:mod:`ecattool.project.machine`).

:func:`lint` builds the :class:`~ecattool.project.machine.Machine` of each project file (every check runs
while it is built); their ``findings`` are what ``ecattool lint`` reports.
"""

from __future__ import annotations

from pathlib import Path

from ecattool.findings import has_errors
from ecattool.project.machine import Machine, load_machine
from ecattool.project.rules import PROJECT_RULES, rule_descriptions

__all__ = ["PROJECT_RULES", "lint", "rule_descriptions"]


def lint(paths: list[str | Path], strict: bool = False) -> tuple[list[Machine], bool]:
    """Lint several project files. Returns their machines and whether the lint failed."""
    machines = [load_machine(p) for p in paths]
    failed = any(has_errors(m.findings, strict) for m in machines)
    return machines, failed
