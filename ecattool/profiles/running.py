"""The device as it runs: the one resolver from what a user names (a built-in profile, an ESI/EDS file with a
selector and revision) to the device lint checks, the exports program, the simulator serves and the live-bus
commands type their values by.

An ESI or EDS file describes a device; a master that starts it plugs each slot's default module in (ETG.2001)
and the drive has the communication objects its file may leave out (1000h, 1018h, 1C00h, 16xxh/1Axxh,
1C12h/1C13h). :func:`as_running` applies that rule (:func:`~ecattool.profiles.generic.complete_generic`, which
plugs the default modules first) once and marks the result a :class:`RunningDevice`, so no later reader
completes it again. A built-in profile device is complete as the family module builds it: it is marked, not
changed.

This module is the only caller of ``plug_default_modules``/``complete_generic`` in the package
(tests/test_fitness.py holds it to that).

Example::

    from ecattool.profiles.running import resolve_device
    dev = resolve_device("samples/esi/etg2001_modular.xml")        # default modules plugged, 1C12h synthesised
    hdt = resolve_device("hdt", product="dgfox")                   # a built-in family
"""

from __future__ import annotations

import copy
import os
from pathlib import Path

from ecattool import esi
from ecattool.esi.model import Device
from ecattool.profiles import load
from ecattool.profiles.generic import complete_generic

__all__ = ["RunningDevice", "as_running", "device_from_file", "device_from_profile", "is_device_file",
           "resolve_device"]

#: file suffixes that name a device description rather than a built-in profile
_FILE_SUFFIXES = (".xml", ".eds", ".dcf")


class RunningDevice(Device):
    """A :class:`~ecattool.esi.model.Device` as it runs: made only by :func:`as_running` (ESI/EDS devices with
    their default modules plugged in and their communication objects completed; built-in profile devices as
    they are). The type is the mark: whoever receives one does not complete it again. Shared by caches: do not
    modify one in place (copy it first)."""

    __slots__ = ()


def _mark(device: Device) -> RunningDevice:
    # same slots, no new state: the class is the mark (the object layout is Device's)
    device.__class__ = RunningDevice
    assert isinstance(device, RunningDevice)
    return device


def as_running(device: Device) -> RunningDevice:
    """``device`` as it runs. A device already marked is returned as it is; a built-in profile device (source
    ``profile:…``) is complete and gets marked (a shallow copy: the caller's object keeps its type); any other
    device (an ESI or EDS reading) is completed on a deep copy (:func:`complete_generic`: default modules
    plugged, missing communication objects synthesised). Never modifies ``device``."""
    if isinstance(device, RunningDevice):
        return device
    if device.source.startswith("profile:"):
        return _mark(copy.copy(device))
    return _mark(complete_generic(device))


def device_from_file(path: str | Path, selector: str | None = None, revision: str | int | None = None,
                     policy: str = "exact") -> RunningDevice:
    """The device ``selector`` (type name, product[:revision] or list index) of the ESI/EDS file at ``path``, as
    it runs. ``revision`` narrows a ``selector`` to that revision (``selector:revision``); ``policy`` is the
    revision policy of :func:`ecattool.esi.select`."""
    sel = f"{selector}:{revision}" if selector and revision is not None and revision != "" else selector
    return as_running(esi.load_device(path, sel, policy))


def device_from_profile(name: str, product: str | None = None, revision: str | int | None = None) -> RunningDevice:
    """A built-in family's device (:func:`ecattool.profiles.load`), marked as it runs."""
    return as_running(load(name, product=product, revision=revision))


def is_device_file(source: str | Path) -> bool:
    """Whether ``source`` names a device description file (an ``.xml``/``.eds``/``.dcf`` name or an existing
    file) rather than a built-in profile name."""
    path = Path(source)
    return path.suffix.lower() in _FILE_SUFFIXES or os.path.isfile(path)  # (Path.is_file raises on a name too long)


def resolve_device(source: str | Path, *, selector: str | None = None, product: str | None = None,
                   revision: str | int | None = None, policy: str = "exact") -> RunningDevice:
    """The device as it runs of ``source``: an ESI/EDS file (``selector``, ``revision`` and ``policy`` choose
    the device) or a built-in profile name (``product`` and ``revision`` choose the model)."""
    if is_device_file(source):
        return device_from_file(source, selector, revision, policy)
    return device_from_profile(str(source), product, revision)
