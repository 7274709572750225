"""``ecattool bus``: look at a live bus."""

from __future__ import annotations

import sys
from typing import TYPE_CHECKING

import click

from ecattool.cli.common import console, hex32, json_option, print_json, table
from ecattool.cli.online import library_option, load_library, open_live, target_option

if TYPE_CHECKING:
    from ecattool.online.scan import ScannedSlave


@click.group(epilog="""\b
Examples:
  ecattool bus scan --target pysoem:eth0 --library esi/
  ecattool bus scan --target sim:hdt,technosoft-ipos --json""")
def bus() -> None:
    """Look at a live bus (read only)."""


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
