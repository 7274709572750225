"""``ecattool bus``: look at a live bus."""

from __future__ import annotations

import json
import sys
import time
from functools import partial
from typing import TYPE_CHECKING

import click

from ecattool.cli.common import console, hex32, json_option, print_json, table
from ecattool.cli.online import (
    library_option,
    load_library,
    open_live,
    reset_bus_given,
    reset_bus_option,
    target_option,
)
from ecattool.online.held import DEFAULT_HOLD_S, MAX_HOLD_S, Hold

if TYPE_CHECKING:
    from ecattool.online.scan import ScannedSlave


@click.group(epilog="""\b
Examples:
  ecattool bus scan --target pysoem:eth0 --library esi/
  ecattool bus scan --target sim:hdt,technosoft-ipos --json
  ecattool bus hold --target pysoem:eth0 --for 600 &
  ecattool bus release --target pysoem:eth0""")
def bus() -> None:
    """Look at a live bus (read only); hold it open for the other commands."""


@bus.command(epilog="""\b
Examples:
  ecattool bus scan --target pysoem:eth0
  ecattool bus scan --target kickcat:eth0 --library esi/ --json
  ecattool bus scan --target sim:hdt,technosoft-ipos,controltechniques""")
@target_option()
@library_option
@json_option
def scan(target: str, library: str | None, as_json: bool) -> None:
    """Every slave: position, identity from the SII and from 1018h (and where they differ), state, AL status
    code, mailbox protocols, DC support, and the library device or built-in family it matches.

    Reads only. Exit status 1 when a slave is unknown (no library device or family matches it) or its SII and
    1018h identities differ.
    """
    from ecattool.online.scan import scan as do_scan

    lib = load_library(library)
    with open_live(target) as live:
        rows = do_scan(live, lib)
    bad = any(r.match is None or r.identity_differs for r in rows)
    if as_json:
        print_json({"target": target, "slaves": [r.to_json() for r in rows],
                    "library_skipped": [{"file": f, "why": w} for f, w in (lib.skipped if lib else [])]})
    else:
        _render_scan(target, rows)
    if bad:
        sys.exit(1)


def _render_scan(target: str, rows: list[ScannedSlave]) -> None:
    """One table row a slave: position, identity, state, AL status, mailbox, DC, the device it matches, notes."""
    t = table(f"{target}: {len(rows)} slaves", ["pos", "vendor", "product", "revision", "state", "AL status",
                                                 "mailbox", "DC", "device", "notes"])
    for r in rows:
        i = r.identity
        notes = [f"SII and 1018h differ in {', '.join(r.identity_differs)}"] if r.identity_differs else []
        notes += r.unknown
        m = r.match
        dev = "unknown" if m is None else f"{m.kind}: {m.name}" + ("" if m.exact or m.kind != "esi" else
                                                                   " (other revision)")
        t.add_row(str(r.position), hex32(i.vendor_id if i else None), hex32(i.product_code if i else None),
                  hex32(i.revision if i else None), r.state,
                  "" if r.al_status is None else f"0x{r.al_status:04X}", ",".join(r.protocols or []),
                  {True: "yes", False: "no", None: "?"}[r.dc], dev, "; ".join(notes))
    console().print(t)


@bus.command(epilog="""\b
Examples:
  ecattool bus hold --target pysoem:eth0 --for 600 &
  ecattool sdo read 0x6041:00 --target pysoem:eth0      (through the held master: no bus init)
  ecattool bus release --target pysoem:eth0""")
@click.option("--target", "target", required=True, metavar="TARGET",
              help="The real master to hold: pysoem:IF or kickcat:IF (a sim:… target is never held).")
@reset_bus_option
@click.option("--for", "seconds", type=click.FloatRange(1, MAX_HOLD_S), default=DEFAULT_HOLD_S, show_default=True,
              metavar="SECONDS", help="End the hold after this long at the latest (at most a day).")
@json_option
def hold(target: str, seconds: float, as_json: bool) -> None:
    """Open the bus once and keep it open for the other ecattool commands, as IgH's master owns its bus.

    Until the hold ends (--for, `ecattool bus release`, Ctrl-C or SIGTERM), every command that reads a live bus
    with the same --target (sdo, bus scan, audit, backup, project new --from-bus, sii read/write) goes through this
    master: no bus init, no slave reset, an `sdo read` in a fraction of the time. Commands that take the slaves
    through INIT (commission, sw, scale explain --target) are refused meanwhile. One command is served at a time,
    for this user and root only. When the hold ends each slave is put back in the state it was found in where
    ecattool can, as every live-bus command does. Prints one line when the bus is held and one when it is
    released (with --json, one JSON object each).
    """
    from ecattool.online.targets import hold_bus

    done = hold_bus(target, seconds, reset_bus=reset_bus_given(), ready=partial(_say_held, as_json))
    _say_released(done, as_json)


def _say_held(as_json: bool, h: Hold) -> None:
    if as_json:
        click.echo(json.dumps({"held": h.name, "pid": h.pid, "slaves": h.slaves, "until": round(h.until, 3)}))
    else:
        click.echo(f"holding {h.name}: {h.slaves} slaves, pid {h.pid}, until "
                   f"{time.strftime('%H:%M:%S', time.localtime(h.until))} (ecattool bus release --target {h.name} "
                   "ends it)")
    sys.stdout.flush()


def _say_released(h: Hold, as_json: bool) -> None:
    if as_json:
        click.echo(json.dumps({"released": h.name, **h.to_json()}))
        return
    click.echo(f"released {h.name} ({h.ended}): {h.commands} commands, {h.requests} requests served")
    for note in h.notes:
        click.echo(f"ecattool: note: {note}", err=True)


@bus.command(epilog="""\b
Examples:
  ecattool bus release --target pysoem:eth0
  ecattool bus release --target kickcat:eth0 --json""")
@click.option("--target", "target", required=True, metavar="TARGET",
              help="The held master: pysoem:IF or kickcat:IF, as `bus hold` was given it (a sim:… target is never held).")
@json_option
def release(target: str, as_json: bool) -> None:
    """End the hold `ecattool bus hold` keeps on a master: it puts the slaves back and closes its master first.
    Exit status 1 when nothing holds it."""
    from ecattool.online.targets import release_bus

    done = release_bus(target)
    if as_json:
        print_json(done)
    else:
        click.echo(f"released {done['target']} (pid {done['pid']}): {done['commands']} commands, "
                   f"{done['requests']} requests served")
