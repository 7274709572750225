"""``ecattool sim serve``: the drives of a project (or profiles, or ESI devices) as virtual slaves on a network
interface, in bus order."""

from __future__ import annotations

import signal
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from types import FrameType
from typing import Any

from ecattool.errors import InputError
from ecattool.esi.model import Device
from ecattool.sim.bus.engine import Bus
from ecattool.sim.esc import Clock
from ecattool.sim.slave import VirtualSlave

#: each slave's local clock starts this far from the previous one's (the master's DC offsets matter)
CLOCK_SPREAD_NS = 1_000_000_007


@dataclass(frozen=True, slots=True)
class Served:
    """One slave of the served bus: its name (project drive name, profile or ESI device) and the slave."""

    name: str
    slave: VirtualSlave

    def describe(self) -> dict[str, Any]:
        ident = self.slave.drive.identity()
        return {"name": self.name, "vendor_id": ident.vendor_id, "product_code": ident.product_code,
                "revision": ident.revision}


def _slaves_for_devices(devices: list[Device]) -> list[VirtualSlave]:
    """The simulated drives ``commission --target sim`` uses for ``devices``, each behind an ESC whose SII is
    what ``ecattool sii build`` makes of the device."""
    from ecattool.sii.builder import build
    from ecattool.sim.drive import Drive
    from ecattool.target.sim import SimTarget

    out = []
    for device, drive in zip(devices, SimTarget.from_devices(devices).slaves()):
        assert isinstance(drive, Drive)
        out.append(VirtualSlave(drive, build(device).to_bytes()))
    return out


def _project(path: Path) -> list[tuple[str, Device]]:
    from ecattool.project.lint import lint_project

    result = lint_project(path)
    if result.loaded is None:
        first = result.findings[0]
        raise InputError(first.message, first.location)
    out = []
    for rd in sorted(result.drives, key=lambda r: r.position):
        if rd.device is None:
            why = next((f for f in rd.findings if f.severity.value == "error"), None)
            raise InputError(f"drive {rd.drive.name!r} cannot be served: its device did not resolve"
                             + (f": {why.message} [{why.rule}]" if why else ""), why.location if why else None)
        out.append((rd.drive.name, rd.device))
    return out


def load_sources(sources: list[str], *, product: str | None = None, revision: str | None = None,
                 selector: str | None = None) -> list[Served]:
    """The slaves of ``sources`` in bus order: a project file (every drive, in its bus order), a built-in
    profile name (``product``/``revision`` choose the model), or an ESI file (``selector`` the device)."""
    from ecattool import esi, profiles

    named: list[tuple[str, Device]] = []
    for src in sources:
        path = Path(src)
        if path.suffix.lower() in (".yaml", ".yml"):
            if not path.is_file():
                raise InputError(f"{src}: no such project file")
            named += _project(path)
        elif path.suffix.lower() == ".xml" or path.is_file():
            device = esi.load_device(path, selector)
            named.append((device.type_name or path.name, device))
        else:
            device = profiles.load(src, product=product, revision=revision)
            named.append((src if product is None else f"{src} {product}", device))
    if not named:
        raise InputError("nothing to serve: name a project file, a profile or an ESI file")
    slaves = _slaves_for_devices([d for _, d in named])
    for i, s in enumerate(slaves):
        s.esc.clock = Clock(offset_ns=i * CLOCK_SPREAD_NS)
    return [Served(name, slave) for (name, _), slave in zip(named, slaves)]


def bus_of(served: list[Served]) -> Bus:
    return Bus([s.slave.esc for s in served])


@contextmanager
def stop_on_signals() -> Iterator[Callable[[], bool]]:
    """A stop condition that becomes true on SIGINT or SIGTERM (the previous handlers come back after)."""
    stopped = [False]

    def handler(signum: int, frame: FrameType | None) -> None:
        stopped[0] = True

    old = {s: signal.signal(s, handler) for s in (signal.SIGINT, signal.SIGTERM)}
    try:
        yield lambda: stopped[0]
    finally:
        for s, h in old.items():
            signal.signal(s, h)


def serve(served: list[Served], ifname: str, on_ready: Callable[[], None],
          max_frames: int | None = None) -> int:
    """Serve the slaves on ``ifname`` until SIGINT/SIGTERM (or ``max_frames``); returns the frames answered."""
    from ecattool.sim.bus.raw import RawTransport

    transport = RawTransport(bus_of(served), ifname)
    try:
        with stop_on_signals() as stop:
            on_ready()
            transport.serve(stop, max_frames)
    finally:
        transport.close()
    return transport.answered
