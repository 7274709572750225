"""The devices of a project's drives in bus order, for whatever puts them on a bus (``ecattool sim serve``)."""

from __future__ import annotations

from pathlib import Path

from ecattool.errors import InputError
from ecattool.esi.model import Device


def devices_in_bus_order(path: str | Path) -> list[tuple[str, Device]]:
    """(drive name, resolved device) of every drive of the project at ``path``, in bus order. A project that
    does not load, or a drive whose device does not resolve, is an InputError naming the file and line."""
    from ecattool.project.lint import lint_project

    result = lint_project(path)
    if result.loaded is None:
        first = result.findings[0]
        raise InputError(first.message, first.location)
    out = []
    for rd in sorted(result.drives, key=lambda r: r.position):
        if rd.device is None:
            why = next((f for f in rd.findings if f.severity.value == "error"), None)
            raise InputError(f"drive {rd.drive.name!r} cannot be simulated: its device did not resolve"
                             + (f": {why.message} [{why.rule}]" if why else ""), why.location if why else None)
        out.append((rd.drive.name, rd.device))
    return out
