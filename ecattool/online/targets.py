"""Opening a live bus from a target spec: the simulator, pysoem or KickCAT."""

from __future__ import annotations

from collections.abc import Sequence

from ecattool.errors import InputError
from ecattool.esi.model import Device
from ecattool.online.live import LiveBus, sim_bus, sim_devices


def open_bus(spec: str, devices: Sequence[Device] = ()) -> LiveBus:
    """The live bus of a target spec: ``sim`` (the simulator with ``devices``, e.g. a project's), ``sim:SOURCE,…``
    (profiles or ESI files), ``pysoem:IF`` or ``kickcat:IF`` (a real master on a network interface)."""
    kind = spec.split(":", 1)[0].strip().lower()
    if kind == "sim":
        from ecattool.sim.slave import drive_for_device

        devs = list(devices) if spec.strip().lower() == "sim" else sim_devices(spec)
        if not devs:
            raise InputError("target 'sim' without a project has no drives: use sim:PROFILE,ESI… "
                             "(e.g. sim:hdt,technosoft-ipos)")
        return sim_bus([drive_for_device(d) for d in devs], spec)
    if kind == "pysoem" and ":" in spec:
        from ecattool.online.pysoem_bus import open_pysoem

        return open_pysoem(spec.split(":", 1)[1])
    if kind == "kickcat" and ":" in spec:
        from ecattool.online.kickcat_bus import open_kickcat

        return open_kickcat(spec.split(":", 1)[1])
    raise InputError(f"unknown target {spec!r}: use sim, sim:PROFILE,ESI…, pysoem:<interface> or kickcat:<interface>")
