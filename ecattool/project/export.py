"""Project → startup export: one :class:`~ecattool.startup.SlaveConfig` per drive, for every master format.

>>> from ecattool.project.export import slave_configs
>>> from ecattool.startup import export
>>> text = export(slave_configs("samples/technosoft_ipos/project.yaml"), "eni")  # doctest: +SKIP

The configuration is what ``ecattool lint`` resolved: the drive's identity, its startup list (PDO
programming, scaling objects, parameters, in that order), the assigned PDOs of the resolved mapping (the
device default where the project gives none), the device's sync managers and the DC settings (an ESI OpMode
by name, or explicit values). A project with lint errors is refused: exporting a configuration that lint
rejects would only move the failure to the plant.
"""

from __future__ import annotations

from pathlib import Path

from ecattool.errors import InputError, Location
from ecattool.findings import Severity
from ecattool.project.lint import ProjectResult, lint_project
from ecattool.project.resolve import ResolvedDrive
from ecattool.startup.config import SlaveConfig


def drive_config(rd: ResolvedDrive) -> SlaveConfig:
    """The slave configuration of one resolved (lint-clean) drive."""
    if rd.device is None:
        raise InputError(f"drive {rd.drive.name!r}: the device did not resolve (see lint)")
    dc = rd.drive.dc
    cfg = SlaveConfig.from_device(
        rd.device, rd.startup, mapping=rd.mapping, position=rd.position, name=rd.drive.name,
        dc_opmode=dc.opmode if dc is not None else None,
        dc_cycle_ns=dc.cycle_ns if dc is not None else None,
        dc_shift_ns=dc.shift_ns if dc is not None else None,
    )
    if dc is not None and dc.assign_activate is not None:
        from ecattool.project.steps import dc_assign_activate

        cfg.dc_assign_activate = dc_assign_activate(rd)
    return cfg


def refuse_errors(result: ProjectResult, what: str) -> None:
    """Raise a located InputError naming the first lint error of ``result`` (and how many there are)."""
    errors = [f for f in result.findings if f.severity is Severity.ERROR]
    if not errors:
        return
    first = errors[0]
    more = f" (and {len(errors) - 1} more; run `ecattool lint {result.path}`)" if len(errors) > 1 else ""
    raise InputError(f"cannot {what}: the project has lint errors, first: {first.message} [{first.rule}]{more}",
                     first.location or Location(result.path))


def slave_configs(path: str | Path) -> list[SlaveConfig]:
    """Lint the project at ``path`` and return one slave configuration per drive, in bus order.

    Raises :class:`~ecattool.errors.InputError` (located at the first error) when lint reports errors.
    """
    result = lint_project(path)
    refuse_errors(result, "export the startup configuration")
    return [drive_config(rd) for rd in sorted(result.drives, key=lambda r: r.position)]
