"""Options and helpers shared by the commands that read a live bus (``bus``, ``sdo``, ``audit``, ``sii read/write``)."""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import click

from ecattool.cli.common import Decorated

if TYPE_CHECKING:
    from ecattool.online.library import Library
    from ecattool.online.live import LiveBus
    from ecattool.project.machine import Machine
    from ecattool.esi.model import Device

TARGET_HELP = ("Where the bus is: pysoem:IF or kickcat:IF (a real master on a network interface), or the simulator: "
               "sim:PROFILE,ESI… (e.g. sim:hdt,technosoft-ipos).")


#: where --reset-bus is kept for the command (click's context meta)
RESET_BUS = "ecattool.reset_bus"


def _reset_bus(ctx: click.Context, param: click.Parameter, value: bool) -> None:
    if value:
        ctx.meta[RESET_BUS] = True


#: ``--reset-bus``, the same on every command that opens a live bus (kept in the context: open_live reads it)
reset_bus_option = click.option(
    "--reset-bus", is_flag=True, expose_value=False, callback=_reset_bus,
    help="Open the bus even when a slave is in SAFE-OP or OP (a real master's bus init takes every slave to INIT: "
         "the machine stops). Without it such a bus is refused. When the command ends each slave is put back in "
         "the state it was found in where ecattool can: SAFE-OP/OP only by audit and backup, as their project "
         "configures the slave; a note names what it could not.")


def target_option(required: bool = True) -> Callable[[Decorated], Decorated]:
    """``--target`` and ``--reset-bus``."""
    target = click.option("--target", "target", required=required, metavar="TARGET", help=TARGET_HELP)

    def both(f: Decorated) -> Decorated:
        return target(reset_bus_option(f))

    return both


def _opened(bus: LiveBus) -> LiveBus:
    """``bus``, whose notes (what closing it could not put back) go to stderr when the command ends."""
    ctx = click.get_current_context(silent=True)

    def say() -> None:
        if not bus.failed:  # after an error, its one line is what the user reads
            for note in bus.notes:
                click.echo(f"ecattool: note: {note}", err=True)

    if ctx is not None:
        ctx.call_on_close(say)
    return bus


def reset_bus_given() -> bool:
    ctx = click.get_current_context(silent=True)
    return bool(ctx is not None and ctx.meta.get(RESET_BUS))


def slave_option(f: Decorated) -> Decorated:
    return click.option("--slave", "slave", type=int, default=0, show_default=True,
                        help="Position of the slave on the bus (0 = first).")(f)


def library_option(f: Decorated) -> Decorated:
    return click.option("--library", "library", type=click.Path(file_okay=False), metavar="DIR",
                        help="A folder of ESI/EDS files to match the slaves against (cached as lint caches ESI).")(f)


def device_option(f: Decorated) -> Decorated:
    return click.option("--device", "device", metavar="DEVICE",
                        help="The slave's device: an ESI file (FILE or FILE@SELECTOR) or a built-in profile name "
                             "(overrides the library and the slave's SDO Information).")(f)


def load_library(folder: str | None) -> Library | None:
    from ecattool.online.library import Library

    return Library(folder) if folder else None


def load_device(text: str | None) -> Device | None:
    """The device ``--device`` names (FILE, FILE@SELECTOR or a built-in profile name): the device of the one-slave
    machine it builds, as a project entry would (default modules plugged, communication objects completed)."""
    if not text:
        return None
    from ecattool.project.machine import Machine

    source, _, selector = text.partition("@")
    return Machine.from_device_flags(source=source, select=selector or None).slaves[0].require_device()


def open_live(target: str, device: Any = None, read_sii: bool = False) -> LiveBus:
    """The live bus of ``target``; ``device`` (``--device``): on a real master its ESI's timeouts bound the waits
    (ecattool.target.timeouts); a simulator's slaves stay the target's own. ``read_sii``: through a master that
    reads no SII (KickCAT) each slave's SII is read before it opens (``project new --from-bus``)."""
    from ecattool.online.targets import open_bus
    from ecattool.target.opener import parse_target

    devices = [device] if device is not None and parse_target(target).kind != "sim" else []
    return _opened(open_bus(target, devices, reset_bus=reset_bus_given(), read_sii=read_sii))


def allow_errors_option(f: Decorated) -> Decorated:
    """``--allow-errors`` on the commands that act on a project over a live bus (the same meaning as on commission;
    the project layer is imported by those commands only, not on the way of ``sdo read``)."""
    from ecattool.project.machine import ALLOW_ERRORS_HELP

    return click.option("--allow-errors", is_flag=True, help=ALLOW_ERRORS_HELP)(f)


def project_machine(project: str, what: str, allow_errors: bool = False) -> Machine:
    """The machine of ``project``, built once for the command: refused (one located line) where it does not load,
    a device does not resolve, or, unless ``allow_errors``, lint reports errors; before any bus is opened."""
    from ecattool.project.machine import load_machine

    machine = load_machine(project)
    machine.refuse_errors(what, allow_errors=allow_errors)
    return machine


def project_bus(machine: Machine, target: str) -> LiveBus:
    """The live bus of ``target`` for a machine (:func:`project_machine`); ``sim`` simulates its drives."""
    from ecattool.online.targets import open_bus

    from functools import partial

    from ecattool.commission.runner import put_back

    # what a bare 'sim' simulates (open_bus reads the spec; a real master or sim:SOURCES ignore them); a slave
    # found in SAFE-OP/OP is taken back there as the project configures it when the command ends
    devices = [device for _, device in machine.devices()]
    return _opened(open_bus(target, devices, reset_bus=reset_bus_given(), put_back=partial(put_back, machine.slaves)))
