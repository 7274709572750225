"""The one place a target spec is read: :func:`parse_target` for every command, :func:`open_target` for those
that act on slaves (``commission``, ``sw verify/download``, ``scale explain --target``), and
``ecattool.online.open_bus`` for those that read a live bus (``bus scan/audit/backup``, ``project new
--from-bus``, ``sii read``). A spec means the same everywhere:

* ``sim`` — the embedded simulator: one simulated slave per device the command has (a project's), in bus
  order; each ESI device runs as it would on a bus (default modules plugged in, communication objects
  completed);
* ``sim:SOURCE,SOURCE…`` — the simulator with these slaves: built-in profile names or ESI files, in bus order;
* ``pysoem:<interface>`` — SOEM through pysoem on that network interface (the optional ``pysoem`` extra); the
  slaves are whatever the bus has;
* ``kickcat:<interface>`` — KickCAT's master on that interface (the optional ``kickcat`` package); it reads a
  live bus (identity, states, SDOs) and does not commission.

Anything else is a :class:`~ecattool.errors.SelectionError` naming the forms. The caller owns the target and
closes it (``Target.close``).
"""

from __future__ import annotations

from collections.abc import Iterable
from types import ModuleType
from typing import TYPE_CHECKING

from ecattool.errors import SelectionError
from ecattool.esi.model import Device
from ecattool.record import FrozenRecord, set_field
from ecattool.target.base import SlaveTarget, Target

if TYPE_CHECKING:
    from ecattool.target.timeouts import BusLimits

#: the forms of a target spec, for help texts and errors
TARGET_FORMS = "'sim', 'sim:PROFILE,ESI…', 'pysoem:<interface>' or 'kickcat:<interface>'"
#: the forms :func:`open_target` opens (KickCAT reads a live bus only)
SLAVE_TARGET_FORMS = "'sim', 'sim:PROFILE,ESI…' or 'pysoem:<interface>'"
#: the kinds of a spec that name a real master on a network interface
MASTERS = ("pysoem", "kickcat")


class TargetSpec(FrozenRecord):
    """A target spec as read: ``kind`` ('sim', 'pysoem' or 'kickcat'), the network ``interface`` of a real
    master, the ``sources`` of a ``sim:`` spec (empty: the slaves the command has)."""

    __slots__ = ("text", "kind", "interface", "sources")
    text: str
    kind: str
    interface: str
    sources: tuple[str, ...]

    def __init__(self, text: str, kind: str, interface: str = "", sources: tuple[str, ...] = ()) -> None:
        set_field(self, "text", text)
        set_field(self, "kind", kind)
        set_field(self, "interface", interface)
        set_field(self, "sources", sources)

    @property
    def own_slaves(self) -> bool:
        """A bare ``sim``: the simulator with the slaves the command has (a project's, a family's drive)."""
        return self.kind == "sim" and not self.sources

    def sim_devices(self, devices: Iterable[Device] = ()) -> list[Device]:
        """What the simulator of this spec holds, the one rule for every command: a ``sim:SOURCE,…`` spec its
        sources' devices (profiles or ESI files), a bare ``sim`` the command's own ``devices`` (a project's
        slaves, a family's drive), in bus order."""
        if self.own_slaves:
            return list(devices)
        from ecattool.sim.bus.serve import device_source

        return [device_source(s)[1] for s in self.sources]


def parse_target(spec: str) -> TargetSpec:
    """``spec`` read (see the module docs); a SelectionError naming the forms when it is none of them."""
    kind, colon, rest = spec.partition(":")
    kind = kind.strip().lower()
    if kind == "sim":
        sources = tuple(s.strip() for s in rest.split(",") if s.strip())
        if colon and not sources:
            raise SelectionError(f"target {spec!r} names no slaves: use sim:PROFILE,ESI… "
                                 "(e.g. sim:hdt,technosoft-ipos), or 'sim' with a project")
        return TargetSpec(spec, "sim", sources=sources)
    if kind in MASTERS and rest.strip():
        return TargetSpec(spec, kind, interface=rest.strip())
    raise SelectionError(f"unknown target {spec!r} (use {TARGET_FORMS})")


def open_target(spec: str, devices: Iterable[Device] = ()) -> Target:
    """The target ``spec`` names (see the module docs); ``devices``: the slaves a bare ``sim`` has, in bus order."""
    parsed = parse_target(spec)
    if parsed.kind == "sim":
        from ecattool.target.sim import SimTarget

        return SimTarget.from_devices(parsed.sim_devices(devices))
    if parsed.kind == "pysoem":
        from ecattool.target.isolated import pysoem_target

        from ecattool.target.timeouts import bus_limits

        # SOEM in a child process: a crash in it cannot end ecattool; waits bounded by the slaves' ESI timeouts
        return pysoem_target(parsed.interface, bus_limits(devices))
    raise SelectionError(f"target {spec!r}: KickCAT reads a live bus (ecattool bus scan, audit, backup; sii read) "
                         f"and does not act on slaves here: use {SLAVE_TARGET_FORMS}")


def open_master(kind: str, interface: str, limits: BusLimits | None = None, module: ModuleType | None = None) -> Target:
    """A real master (``kind`` 'pysoem' or 'kickcat', :data:`MASTERS`) on ``interface`` in this process, every slave
    in PRE-OP, for reading a live bus (``ecattool.online.targets.open_bus`` runs it in the master's child process):
    no process data is set up, the commands that read a bus never take a slave past PRE-OP. ``limits``: the slaves'
    timeouts; ``module``: the binding (a test's fake), else the installed one."""
    if kind == "pysoem":
        from ecattool.target.pysoem import PysoemTarget

        return PysoemTarget(interface, pysoem_module=module, keep_cycling=False, limits=limits)
    if kind == "kickcat":
        from ecattool.target.kickcat import KickcatTarget

        return KickcatTarget(interface, module, limits)
    raise SelectionError(f"unknown master {kind!r} (use {' or '.join(MASTERS)})")


def slave_at(target: Target, position: int) -> SlaveTarget:
    """The slave at bus ``position`` of ``target`` (a SelectionError naming how many slaves the bus has)."""
    slaves = target.slaves()
    if not 0 <= position < len(slaves):
        raise SelectionError(f"no slave at bus position {position} (the bus has {len(slaves)})")
    return slaves[position]
