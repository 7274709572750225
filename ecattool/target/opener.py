"""The one place a target spec becomes a target: ``open_target("sim", devices)`` or ``open_target("pysoem:eth0")``.

Every command that talks to slaves (``commission``, ``sw verify/download``, ``scale explain --target``, and
the bus commands) opens its target here, so a spec means the same everywhere:

* ``sim`` — the embedded simulator: one simulated slave per device in ``devices``, in that (bus) order;
  each ESI device runs as it would on a bus (default modules plugged in, communication objects completed);
* ``pysoem:<interface>`` — a real master on that network interface (the optional ``pysoem`` extra); the
  slaves are whatever the bus has, ``devices`` is not used.

Anything else is a :class:`~ecattool.errors.SelectionError` naming the forms. The caller owns the target and
closes it (``Target.close``).
"""

from __future__ import annotations

from collections.abc import Iterable

from ecattool.errors import SelectionError
from ecattool.esi.model import Device
from ecattool.target.base import SlaveTarget, Target

#: the forms of a target spec, for help texts and errors
TARGET_FORMS = "'sim' or 'pysoem:<interface>'"


def open_target(spec: str, devices: Iterable[Device] = ()) -> Target:
    """The target ``spec`` names (see the module docs); ``devices``: the slaves a simulator has, in bus order."""
    kind, _, rest = spec.partition(":")
    kind = kind.strip().lower()
    if kind == "sim" and not rest:
        from ecattool.target.sim import SimTarget

        return SimTarget.from_devices(devices)
    if kind == "pysoem" and rest.strip():
        from ecattool.target.pysoem import PysoemTarget

        return PysoemTarget(rest.strip())
    raise SelectionError(f"unknown target {spec!r} (use {TARGET_FORMS})")


def slave_at(target: Target, position: int) -> SlaveTarget:
    """The slave at bus ``position`` of ``target`` (a SelectionError naming how many slaves the bus has)."""
    slaves = target.slaves()
    if not 0 <= position < len(slaves):
        raise SelectionError(f"no slave at bus position {position} (the bus has {len(slaves)})")
    return slaves[position]
