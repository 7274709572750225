"""``ecattool sim serve``: the drives of a project (or profiles, or ESI devices) as virtual slaves on a network
interface, in bus order."""

from __future__ import annotations

import gc
import signal
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from types import FrameType
from typing import TYPE_CHECKING, Any

from ecattool.errors import InputError
from ecattool.esi.model import Device
from ecattool.sim.bus.engine import Bus
from ecattool.sim.esc import Clock
from ecattool.sim.slave import VirtualSlave, drive_for_device, served_sii

if TYPE_CHECKING:
    from ecattool.sim.bus.loop import FrameFault

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


def device_source(source: str, *, product: str | None = None, revision: str | None = None,
                  selector: str | None = None) -> tuple[str, Device]:
    """(name, device as it runs) of a built-in profile name (``product``/``revision`` choose the model) or an
    ESI/EDS file (``selector`` the device): :func:`ecattool.profiles.running.resolve_device`."""
    from ecattool.profiles.running import device_from_file, device_from_profile, is_device_file

    if is_device_file(source):
        device = device_from_file(source, selector)
        return device.type_name or Path(source).name, device
    device = device_from_profile(source, product=product, revision=revision)
    return (source if product is None else f"{source} {product}"), device


def virtual_slaves(named: list[tuple[str, Device]]) -> list[Served]:
    """One virtual slave per device, in bus order: the drive ``commission --target sim`` would simulate for
    it, behind an ESC whose SII is what ``ecattool sii build`` makes of the device."""
    if not named:
        raise InputError("nothing to serve: name a project file, a profile or an ESI file")
    out = []
    for i, (name, device) in enumerate(named):
        slave = VirtualSlave(drive_for_device(device), served_sii(device),
                             clock=Clock(offset_ns=i * CLOCK_SPREAD_NS))
        why = slave.unservable()
        if why is not None:
            raise InputError(f"cannot serve slave {i} ({name}, {device.type_name or '?'} vendor 0x"
                             f"{device.vendor_id or 0:08X} product 0x{device.product_code:08X}): {why}")
        out.append(Served(name, slave))
    return out


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
          max_frames: int | None = None, fault: "FrameFault | None" = None, workers: int | None = None) -> int:
    """Serve the slaves on ``ifname`` until SIGINT/SIGTERM (or ``max_frames``); returns the frames answered.
    ``fault`` sees every frame before the bus (tests: lost and spoilt frames, see RawTransport). ``workers``:
    how many processes serve the line (:mod:`ecattool.sim.bus.split`); None chooses from the number of drives
    and the cores (:func:`~ecattool.sim.bus.split.choose_workers`).

    While it serves, each drive runs on its own clock (:attr:`VirtualSlave.own_clock`: its cycle time or SYNC0
    paces its motion, not the master's frames), the drives keep no event log (nobody can read it from the wire,
    and it would grow for as long as the server runs), and what exists when serving starts (the drives, their
    dictionaries and SII images, the imported modules) is moved out of the garbage collector's way
    (``gc.freeze``): a full collection over 8 drives' objects takes ~12 ms, twelve cycles of a 1 kHz bus;
    frozen, microseconds. All come back as they were when serving stops."""
    from ecattool.sim.bus import raw, split

    count = split.choose_workers(len(served)) if workers is None else max(1, min(workers, len(served)))
    logging = [s.slave.drive.record_events for s in served]
    clocks = [s.slave.own_clock for s in served]
    for s in served:
        s.slave.drive.record_events = False
        s.slave.own_clock = True  # on the wire a drive runs on its own clock, not on the master's frames
    gc.collect()
    gc.freeze()  # before the workers are forked: they inherit the frozen set-up
    transport: "raw.RawTransport | split.SplitTransport | None" = None
    try:
        if count == 1:
            transport = raw.RawTransport(bus_of(served), ifname, fault)
        else:
            transport = split.SplitTransport([s.slave.esc for s in served], split.split(len(served), count),
                                             ifname, fault)
        with stop_on_signals() as stop:
            on_ready()
            transport.serve(stop, max_frames)
    finally:
        gc.unfreeze()
        for s, on, own in zip(served, logging, clocks):
            s.slave.drive.record_events = on
            s.slave.own_clock = own
        if transport is not None:
            transport.close()
    return transport.answered
