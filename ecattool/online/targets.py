"""Opening a live bus from a target spec (read by :func:`ecattool.target.opener.parse_target`): the simulator,
pysoem or KickCAT."""

from __future__ import annotations

from collections.abc import Callable, Sequence

from ecattool.errors import SelectionError
from ecattool.esi.model import Device
from ecattool.online.live import LiveBus, sim_bus
from ecattool.target.opener import parse_target, sim_devices


def open_bus(spec: str, devices: Sequence[Device] = ()) -> LiveBus:
    """The live bus of a target spec: ``sim`` (the simulator with ``devices``, e.g. a project's), ``sim:SOURCE,…``
    (profiles or ESI files), ``pysoem:IF`` or ``kickcat:IF`` (a real master on a network interface)."""
    parsed = parse_target(spec)
    if parsed.kind == "sim":
        from ecattool.sim.slave import drive_for_device

        devs = sim_devices(parsed, devices)
        if not devs:
            raise SelectionError("target 'sim' without a project has no slaves: use sim:PROFILE,ESI… "
                                 "(e.g. sim:hdt,technosoft-ipos)")
        return sim_bus([drive_for_device(d) for d in devs], spec)
    # a real master runs in a child process (ecattool.target.isolated): one that crashes or hangs on what a slave
    # answers becomes a one-line error naming the slave and the object, never the end of ecattool
    if parsed.kind == "pysoem":
        from ecattool.online.pysoem_bus import open_pysoem
        from ecattool.target.pysoem import _import_pysoem

        _import_pysoem()
        return isolated_bus(spec, lambda: open_pysoem(parsed.interface))
    from ecattool.online.kickcat_bus import open_kickcat
    from ecattool.target.kickcat import import_kickcat

    import_kickcat()
    return isolated_bus(spec, lambda: open_kickcat(parsed.interface))


def isolated_bus(spec: str, opener: Callable[[], LiveBus]) -> LiveBus:
    """The live bus ``opener`` opens, served from a child process (:class:`~ecattool.target.isolated.MasterProcess`)."""
    from ecattool.target.isolated import MasterProcess, RemoteSlave

    master = MasterProcess(spec, opener, lambda bus: bus.slaves)
    return LiveBus(spec, [RemoteSlave(master, p) for p in master.positions], closer=master.close)
