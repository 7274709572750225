"""The devices of a project's slaves in bus order, for whatever puts them on a bus (``ecattool sim serve``), and
the devices of ``sim serve``'s sources (project files, profile names, ESI files) in bus order."""

from __future__ import annotations

from collections.abc import Iterable
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


def is_project_file(source: str) -> bool:
    """Whether a source of ``sim serve`` names a project file (YAML) rather than a profile or a device file."""
    return source.lower().endswith((".yaml", ".yml"))


def served_devices(sources: Iterable[str], *, product: str | None = None, revision: str | None = None,
                   selector: str | None = None, allow_errors: bool = False) -> list[tuple[str, Device]]:
    """(name, device as it runs) of every source in bus order, as ``sim serve`` puts them on a bus: a project file
    gives each of its slaves in the project's bus order (:func:`devices_in_bus_order`, refused on lint errors unless
    ``allow_errors``), a built-in profile name or an ESI file one device
    (:func:`ecattool.sim.bus.serve.device_source`: ``product``/``revision`` choose a profile's model, ``selector``
    a file's device)."""
    from ecattool.sim.bus.serve import device_source

    named: list[tuple[str, Device]] = []
    for source in sources:
        if is_project_file(source):
            named += devices_in_bus_order(source, allow_errors)
        else:
            named.append(device_source(source, product=product, revision=revision, selector=selector))
    return named
