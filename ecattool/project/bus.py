"""The devices of a project's slaves in bus order, for whatever puts them on a bus (``ecattool sim serve``)."""

from __future__ import annotations

from pathlib import Path

from ecattool.esi.model import Device
from ecattool.project.machine import Machine, load_machine


def devices_in_bus_order(path: str | Path | Machine, allow_errors: bool = False) -> list[tuple[str, Device]]:
    """(slave name, device as it runs) of every slave of the project at ``path``, in bus order. A project that
    does not load, or a slave whose device does not resolve, is an InputError naming the file and line; a
    project with other lint errors too unless ``allow_errors`` (``Machine.refuse_errors``)."""
    machine = path if isinstance(path, Machine) else load_machine(path)
    machine.refuse_errors("simulate the project", allow_errors=allow_errors)
    return machine.devices()
