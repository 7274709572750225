"""A live bus: the slaves behind a master as ecattool reads them (identity, state, AL status, SDO, SDO
Information, SII), on every target: the embedded simulator, SOEM through pysoem, KickCAT.

Every target's slaves are :class:`ecattool.target.base.LiveSlave` objects, one adapter module per master
(``ecattool.target.sim``, ``.pysoem``, ``.kickcat``); what a master's binding cannot do raises
:class:`ecattool.target.base.Unsupported`. A bus is opened by :func:`ecattool.online.targets.open_bus`.
"""

from __future__ import annotations

import weakref
from collections.abc import Callable
from typing import Any

from ecattool.errors import InputError, TargetError
from ecattool.esi.model import Device
from ecattool.record import FrozenRecord, Record, set_field
from ecattool.target.base import LiveSlave


class LiveBus(Record):
    """The slaves of one target, in bus order. ``spec`` names the target (``sim``, ``pysoem:eth0``…)."""

    __slots__ = ("spec", "slaves", "closer", "write_log", "devices", "notes", "found", "failed", "master")
    spec: str
    slaves: list[LiveSlave]
    closer: Callable[[], None] | None
    #: the simulator's log of writes (SDO downloads, SII writes) since the bus was opened; None on a real master
    write_log: list[str] | None
    #: the devices a simulator bus was made of (its own dictionaries), by position
    devices: list[Device]
    #: what closing the bus did or could not do (a slave put back in OP, or found in OP and left in PRE-OP), one
    #: line each
    notes: list[str]
    #: each slave's AL state as found before the master reset the bus (``bus_state.Found``; empty: not known)
    found: list[Any]
    #: whether the ``with`` block that used the bus ended with an exception (its error is what a user reads then)
    failed: bool
    #: the child process a real master's slaves are served from (``ecattool.target.isolated.MasterProcess``,
    #: what ``ecattool bus hold`` keeps); None for the simulator and for a bus read through a holder
    master: Any

    def __init__(self, spec: str, slaves: list[LiveSlave], closer: Callable[[], None] | None = None,
                 write_log: list[str] | None = None, devices: list[Device] | None = None,
                 notes: list[str] | None = None, found: list[Any] | None = None, failed: bool = False,
                 master: Any = None) -> None:
        self.spec = spec
        self.slaves = slaves
        self.closer = closer
        self.write_log = write_log
        self.devices = [] if devices is None else devices
        self.notes = [] if notes is None else notes
        self.found = [] if found is None else found
        self.failed = failed
        self.master = master

    def found_at(self, position: int) -> Any:
        """The state as found (:attr:`found`: ``ecattool.online.found.Found``) of the slave at ``position``, or
        None where it was not read."""
        return next((f for f in self.found if getattr(f, "position", None) == position), None)

    def slave(self, position: int) -> LiveSlave:
        if not 0 <= position < len(self.slaves):
            raise InputError(f"no slave at position {position}: the bus on {self.spec} has {len(self.slaves)}")
        return self.slaves[position]

    def close(self) -> None:
        if self.closer is not None:
            self.closer()
            self.closer = None

    def __enter__(self) -> "LiveBus":
        return self

    def __exit__(self, *exc: object) -> None:
        self.failed = exc[0] is not None
        self.close()


# --------------------------------------------------------------------------------------------- as found
#: the mailbox protocol bit of CoE in SII word 0x1C (ETG.2010)
MBX_COE = 0x0004


class SiiFacts(FrozenRecord):
    """What a slave's SII says about how to talk to it: its mailbox protocols (SII word 0x1C; 0 where its
    standard receive mailbox, word 0x19, has no size: the slave has no mailbox) and its name (the general
    category's); ``protocols`` None where the target gives no SII (KickCAT's binding)."""

    __slots__ = ("protocols", "name")
    protocols: int | None
    name: str

    def __init__(self, protocols: int | None, name: str = "") -> None:
        set_field(self, "protocols", protocols)
        set_field(self, "name", name)

    @property
    def coe(self) -> bool | None:
        """Whether SDOs can reach the slave: True, False (no CoE mailbox: never send it one), None (unknown)."""
        return None if self.protocols is None else bool(self.protocols & MBX_COE)


_FACTS: "weakref.WeakKeyDictionary[Any, SiiFacts]" = weakref.WeakKeyDictionary()


def sii_facts(slave: Any, sii: bytes | None = None) -> SiiFacts:
    """The :class:`SiiFacts` of ``slave``, read from its SII once (kept for as long as the slave object lives);
    ``sii``: its SII image where the caller has read it already."""
    try:
        return _FACTS[slave]
    except (KeyError, TypeError):
        pass
    from ecattool.sii.image import parse

    try:
        image = parse(slave.sii_read() if sii is None else sii, source=f"slave {slave.position} SII")
    except TargetError:  # Unsupported (no SII through this master), or the read failed: not known
        facts = SiiFacts(None)
    except InputError:  # an SII that does not parse: the header words are still the slave's
        facts = SiiFacts(None)
    else:
        h = image.header
        g = image.general
        name = image.strings[g.name_idx - 1] if g is not None and 0 < g.name_idx <= len(image.strings) else ""
        has_mailbox = h.std_rx_size not in (0, 0xFFFF) and h.mailbox_protocols != 0xFFFF
        facts = SiiFacts(h.mailbox_protocols if has_mailbox else 0, name)
    try:
        _FACTS[slave] = facts
    except TypeError:
        pass  # an object that takes no weak reference: read again next time
    return facts


def describe_slave(slave: Any) -> str:
    """"slave N (NAME, vendor 0x…, product 0x…, revision 0x…)": a slave named as a user finds it on the bus
    (what is not known is left out)."""
    parts = []
    try:
        known = _FACTS.get(slave)
    except TypeError:
        known = None
    name = known.name if known is not None else ""  # never a new SII read for a slave that may not answer
    if name:
        parts.append(name)
    try:
        ident = slave.identity()
    except Exception:  # noqa: BLE001 - naming a slave that does not answer must not fail in turn
        ident = None
    if ident is not None:
        parts.append(f"vendor 0x{ident.vendor_id:08X}, product 0x{ident.product_code:08X}, "
                     f"revision 0x{ident.revision:08X}")
    return f"slave {slave.position}" + (f" ({', '.join(parts)})" if parts else "")
