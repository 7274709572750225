"""Lint: the findings of the machine a project sets up (:mod:`ecattool.project.machine`).

``lint_project`` builds the :class:`~ecattool.project.machine.Machine` (every check runs while it is built)
and returns it; its ``findings`` are what ``ecattool lint`` reports.
"""

from __future__ import annotations

from pathlib import Path

from ecattool.findings import has_errors
from ecattool.project.machine import Machine, build_slave, load_machine
from ecattool.project.rules import PROJECT_RULES, rule_descriptions

__all__ = ["PROJECT_RULES", "ProjectResult", "build_drive", "lint", "lint_project", "rule_descriptions"]

#: the former name of :class:`~ecattool.project.machine.Machine`
ProjectResult = Machine
#: the former name of :func:`~ecattool.project.machine.build_slave`
build_drive = build_slave


def lint_project(path: str | Path) -> Machine:
    """The machine of the project at ``path``; its ``findings`` are the lint findings."""
    return load_machine(path)


def lint(paths: list[str | Path], strict: bool = False) -> tuple[list[Machine], bool]:
    """Lint several project files. Returns the results and whether the lint failed."""
    results = [lint_project(p) for p in paths]
    failed = any(has_errors(r.findings, strict) for r in results)
    return results, failed
