"""Modular devices (ETG.2001 slots): the device as an ESI-configured master starts it, each slot's default
module plugged in."""

from __future__ import annotations

from ecattool.esi.model import Device


def expand_default_modules(device: Device) -> Device:
    """A modular device (ETG.2001 slots) with each slot's default module plugged in: the module PDOs are
    added with the slot's PDO increment, their entries (and the module dictionaries) with the slot's index
    increment, as an ESI-configured master does before it starts the slave.

    The rule is the one lint and the exports use (:func:`ecattool.profiles.generic.plug_default_modules`): the
    simulator serves the device lint checked, never a second reading of the slots."""
    from ecattool.profiles.generic import plug_default_modules

    return plug_default_modules(device)
