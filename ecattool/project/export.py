"""Project → startup export: one :class:`~ecattool.startup.SlaveConfig` per drive, for every master format.

>>> from ecattool.project.export import slave_configs
>>> from ecattool.startup import export
>>> text = export(slave_configs("samples/technosoft_ipos/project.yaml"), "eni")  # doctest: +SKIP

The configuration is what ``ecattool lint`` resolved: the drive's identity, its startup list (PDO
programming, scaling objects, parameters, in that order), the assigned PDOs of the resolved mapping (the
device default where the project gives none), the device's sync managers and the DC settings (an ESI OpMode
by name, or explicit values). A project with lint errors is refused (``Machine.refuse_errors``, the policy
every command shares): exporting a configuration that lint rejects would only move the failure to the plant;
``allow_errors`` exports it anyway.
"""

from __future__ import annotations

from pathlib import Path

from ecattool.findings import Finding, Severity
from ecattool.project.machine import Machine, load_machine
from ecattool.startup.config import SlaveConfig


def slave_configs(path: str | Path | Machine, allow_errors: bool = False) -> list[SlaveConfig]:
    """One slave configuration per slave of the project at ``path`` (or of a built Machine), in bus order.

    Raises :class:`~ecattool.errors.InputError` (located at the first error) when lint reports errors, unless
    ``allow_errors``.
    """
    machine = path if isinstance(path, Machine) else load_machine(path)
    return machine.configs(allow_errors=allow_errors)


#: lint rules whose warnings concern what an export writes (the identity a master checks)
EXPORT_RULES = frozenset({"esi-product-zero"})


def export_warnings(machine: Machine, names: set[str] | None = None) -> list[Finding]:
    """The lint warnings of the slaves called ``names`` (all by default) that concern what an export writes: a
    product code 0 the configuration will expect (an EDS without ProductNumber). ``startup export --project``
    prints them, one line each, so that a warning lint gives is not lost in a file written without a word."""
    seen: set[tuple[str, str, str]] = set()
    out = []
    for s in machine.in_bus_order():
        if names is not None and s.name not in names:
            continue
        for f in s.findings:
            key = (f.rule, f.message, str(f.location))
            if f.rule in EXPORT_RULES and f.severity is Severity.WARNING and key not in seen:
                seen.add(key)
                out.append(f)
    return out
