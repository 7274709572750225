"""Opening a live bus from a target spec (read by :func:`ecattool.target.opener.parse_target`): the simulator,
pysoem or KickCAT, each through its one adapter module (``ecattool.target.sim``, ``.pysoem``, ``.kickcat``)."""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence
from types import ModuleType
from typing import TYPE_CHECKING, Any

from ecattool.errors import SelectionError
from ecattool.od.model import EcState
from ecattool.online import held
from ecattool.online.live import LiveBus
from ecattool.target.base import LiveSlave, SlaveTarget, Target
from ecattool.target.opener import MASTERS, open_master, open_target, parse_target, slave_at
from ecattool.target.remote import RemoteSlave
from ecattool.target.timeouts import KICKCAT_SII_S, SII_S, BusLimits, bus_limits

if TYPE_CHECKING:
    from ecattool.esi.model import Device
    from ecattool.online.bus_state import Found, PutBack

# the bus state read (its raw frames) and the master's child process are loaded by the functions that open a bus
# with a master of their own: a command that reads through a held bus (ecattool.online.held) needs neither


def open_bus(spec: str, devices: Sequence[Device] = (), reset_bus: bool = False,
             put_back: PutBack | None = None, read_sii: bool = False) -> LiveBus:
    """The live bus of a target spec: ``sim`` (the simulator with ``devices``, e.g. a project's), ``sim:SOURCE,…``
    (profiles or ESI files), ``pysoem:IF`` or ``kickcat:IF`` (a real master on a network interface).

    A real master resets every slave when it opens the bus: first each slave's state is read
    (:mod:`ecattool.online.bus_state`), a bus with slaves in SAFE-OP or OP is refused unless ``reset_bus``, and
    when the bus is closed each slave is put back where it was found where that can be done (what could not is
    in the bus's ``notes``): INIT and PRE-OP always, SAFE-OP and OP through ``put_back`` (a command with a
    project: ``ecattool.commission.runner.put_back`` with its slaves; :func:`bus_state.restore`). ``read_sii``:
    through KickCAT (whose binding reads no SII) each slave's SII image is read before the master opens, through
    its ESC's EEPROM interface (:func:`bus_state.with_sii`; in the bus's ``found``), for ``project new
    --from-bus``: the model the SII names, the mailbox it has, its identity where it has no 1018h.

    Where ``ecattool bus hold`` holds the master (:mod:`ecattool.online.held`), the bus is read through it: no bus
    init, nothing reset, nothing to put back; ``found`` is what the holder found."""
    parsed = parse_target(spec)
    if parsed.kind == "sim":
        from ecattool.sim.slave import drive_for_device

        devs = parsed.sim_devices(devices)
        if not devs:
            raise SelectionError("target 'sim' without a project has no slaves: use sim:PROFILE,ESI… "
                                 "(e.g. sim:hdt,technosoft-ipos)")
        return sim_bus([drive_for_device(d) for d in devs], spec)
    through = held.held_bus(held.hold_name(parsed.kind, parsed.interface), spec, bus_limits(devices))
    if through is not None:
        return through
    from ecattool.online import bus_state

    found = bus_state.guard(parsed.interface, reset_bus, sii=read_sii and parsed.kind == "kickcat")
    if parsed.kind == "kickcat" and put_back is not None:
        put_back = kickcat_stays_preop  # nothing written to a slave that cannot be taken further
    # how long to wait: the slaves' own ESI timeouts where the command has devices (a project, --device), the bus
    # init budgeted for as many slaves as the state read found (ecattool.target.timeouts)
    limits = bus_limits(devices, len(found) or None, KICKCAT_SII_S if parsed.kind == "kickcat" else SII_S)
    # a real master runs in a child process (ecattool.target.isolated): one that crashes or hangs on what a slave
    # answers becomes a one-line error naming the slave and the object, never the end of ecattool
    if parsed.kind == "pysoem":
        from ecattool.target.pysoem import _import_pysoem

        _import_pysoem()  # a missing extra is said here, and the child starts with the module loaded
    else:
        from ecattool.target.kickcat import import_kickcat

        import_kickcat()
    bus_state.settle()  # the state read's socket, closed meanwhile, is not the master's child's to hold
    return _restoring(isolated_bus(spec, lambda: open_live(parsed.kind, parsed.interface, limits=limits), limits),
                      found, put_back)


def hold_bus(spec: str, seconds: float, reset_bus: bool = False,
             ready: Callable[[held.Hold], None] = lambda h: None) -> held.Hold:
    """Hold the bus of a real master (``ecattool bus hold``, :func:`ecattool.online.held.hold`): opened as
    :func:`open_bus` opens it (refused where a slave is in SAFE-OP or OP, unless ``reset_bus``; through KickCAT each
    slave's SII read first), served to the other commands for ``seconds`` at the most, then put back as found."""
    parsed = parse_target(spec)
    name = held.hold_name(parsed.kind, parsed.interface)
    return held.hold(name, lambda: open_bus(spec, reset_bus=reset_bus, read_sii=parsed.kind == "kickcat"),
                     seconds, ready)


def release_bus(spec: str) -> dict[str, Any]:
    """End the hold on the master ``spec`` names (``ecattool bus release``, :func:`ecattool.online.held.release`);
    the holder's summary (``target``, ``pid``, ``commands``, ``requests``, ``notes``)."""
    parsed = parse_target(spec)
    return held.release(held.hold_name(parsed.kind, parsed.interface))


def kickcat_stays_preop(wanted: Sequence[tuple[Any, EcState]]) -> list[str]:
    """Through KickCAT a slave found in SAFE-OP/OP stays in PRE-OP: its binding requests a state for the whole bus
    only (``Bus.request_state``) and sets up no process data here, so nothing of the project is written."""
    return [f"slave {s.position} ({state.value}) was left in PRE-OP: KickCAT's Python binding takes no single slave "
            f"to a state, ecattool cannot take it back to {state.value} (pysoem:IF can)" for s, state in wanted]


def open_live(kind: str, ifname: str, module: ModuleType | None = None, limits: BusLimits | None = None) -> LiveBus:
    """A real master (``kind`` 'pysoem' or 'kickcat') on ``ifname`` in this process, every slave in PRE-OP, as a
    live bus (:func:`ecattool.target.opener.open_master`); ``module``: the binding (a test's fake)."""
    target = open_master(kind, ifname, limits, module)
    return LiveBus(f"{kind}:{ifname}", _live(target.slaves()), closer=target.close)


def sim_bus(drives: Iterable[Any], spec: str = "sim") -> LiveBus:
    """A live bus of simulated drives (e.g. those of a ``SimTarget`` a test commissioned), each with the SII
    ``ecattool sii build`` makes of its device (as ``sim serve`` gives it): :func:`ecattool.target.sim.live_slaves`."""
    from ecattool.target.sim import live_slaves

    log: list[str] = []
    slaves = live_slaves(drives, log)
    return LiveBus(spec, list(slaves), write_log=log, devices=[s.drive.device for s in slaves])


def _live(slaves: Iterable[Any]) -> list[LiveSlave]:
    """The slaves of a master adapter, each a :class:`LiveSlave` (every adapter's slave class is one)."""
    out: list[LiveSlave] = []
    for s in slaves:
        if not isinstance(s, LiveSlave):
            raise TypeError(f"{type(s).__name__} is not a LiveSlave")
        out.append(s)
    return out


def open_guarded(spec: str, devices: Sequence[Device] = (), reset_bus: bool = False) -> Target:
    """The target ``spec`` names (:func:`ecattool.target.opener.open_target`, for the commands that act on slaves:
    ``commission``, ``sw verify/download/upload``, ``scale explain --target``), a real master's bus first read
    for slaves in SAFE-OP or OP and refused where it has any, unless ``reset_bus`` (:func:`bus_state.guard`):
    these commands take every slave through INIT too, and a running machine is never stopped by surprise."""
    parsed = parse_target(spec)
    if parsed.kind in MASTERS:
        held.refuse_if_held(held.hold_name(parsed.kind, parsed.interface),
                            "this command takes every slave through INIT with a master of its own")
        from ecattool.online import bus_state

        bus_state.guard(parsed.interface, reset_bus)
        bus_state.settle()
    return open_target(spec, devices)


def _restoring(bus: LiveBus, found: Sequence[Found], put_back: PutBack | None = None) -> LiveBus:
    """``bus``, closed with each slave put back in the state it was found in (bus_state.restore; SAFE-OP and OP
    through ``put_back``) first."""
    from ecattool.online import bus_state

    close = bus.closer
    bus.found = list(found)

    def closer() -> None:
        try:
            bus.notes.extend(bus_state.restore(bus.slaves, found, put_back))
        finally:
            if close is not None:
                close()

    bus.closer = closer
    return bus


def isolated_bus(spec: str, opener: Callable[[], LiveBus], limits: BusLimits | None = None) -> LiveBus:
    """The live bus ``opener`` opens, served from a child process (:class:`~ecattool.target.isolated.MasterProcess`);
    ``limits``: how long it may take (the slaves' timeouts)."""
    from ecattool.target.isolated import MasterProcess

    master = MasterProcess(spec, opener, lambda bus: bus.slaves, limits=limits)
    return LiveBus(spec, [RemoteSlave(master, p) for p in master.positions], closer=master.close, master=master)


def open_slave(spec: str, devices: Sequence[Device], position: int, reset_bus: bool = False, *,
               in_preop: bool = False) -> SlaveTarget:
    """The one slave a command acts on (``sw verify/download/upload``, ``scale explain --target``): the slave at bus
    ``position`` of the target ``spec``, opened by :func:`open_guarded` with ``devices`` (what a bare ``sim``
    simulates, and whose timeouts a real bus takes). A bare ``sim`` holds just those devices: its first drive
    answers as the slave asked for (its ``position`` is ``position``). ``in_preop``: a simulated slave is taken to
    PRE-OP first (it starts in INIT; a real master opens its slaves in PRE-OP)."""
    parsed = parse_target(spec)
    tgt = open_guarded(spec, devices, reset_bus)
    if not parsed.own_slaves:
        found = slave_at(tgt, position)
    else:
        found = slave_at(tgt, 0)
        found.position = position
    if in_preop and parsed.kind == "sim":
        found.request_state(EcState.PREOP)
    return found
