"""``ecattool sim``: built-in drive profiles and the embedded drive simulator."""

from __future__ import annotations

import sys
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

import click

from ecattool.cli.common import (
    console,
    dump_json,
    json_option,
    output_option,
    policy_option,
    print_json,
    table,
    write_output,
)
from ecattool.cli.paths import InputFile
from ecattool.errors import EcatToolError, Location, TargetError

if TYPE_CHECKING:
    from ecattool.esi.model import Device
    from ecattool.sim.bus.serve import Served
    from ecattool.sim.drive import Drive
    from ecattool.sim.script import Line, Transcript


@click.group("sim", epilog="""\b
Examples:
  ecattool sim profiles
  ecattool sim show technosoft-ipos --revision F515I
  ecattool sim run hdt steps.yaml --json""")
def sim() -> None:
    """Built-in drive profiles and the embedded drive simulator.

    The simulator answers SDOs byte for byte as the drive would (abort codes included), runs the
    EtherCAT and CiA-402 state machines and exchanges process data through the current PDO mapping.
    """


@sim.command("profiles", epilog="""\b
Examples:
  ecattool sim profiles
  ecattool sim profiles --json""")
@json_option
def profiles_cmd(as_json: bool) -> None:
    """List the built-in drive families with their models, product codes and firmware revisions."""
    from ecattool import profiles

    rows: list[dict[str, Any]] = []  # JSON rows
    for p in profiles.list_profiles():
        for prod in p.products:
            rows.append({"profile": p.name, "vendor_id": p.vendor_id, "vendor": p.vendor_name, "product": prod.name,
                         "title": prod.title, "product_code": prod.product_code, "revisions": list(prod.revisions),
                         "default_revision": prod.default_revision})
    if as_json:
        print_json(rows)
        return
    t = table(None, ["profile", "product", "title", "product code", "revisions"])
    for r in rows:
        t.add_row(r["profile"], r["product"], r["title"], f"0x{r['product_code']:08X}", " ".join(r["revisions"]))
    console().print(t)


@sim.command("show", epilog="""\b
Examples:
  ecattool sim show technosoft-ipos --revision F515I
  ecattool sim show controltechniques --product digitax-st --json
  ecattool sim show hdt --objects""")
@click.argument("profile")
@click.option("--product", help="Model of the family (see 'ecattool sim profiles').")
@click.option("--revision", help="Firmware revision (Technosoft F515K, Control Techniques 01.02.00).")
@click.option("--objects/--no-objects", default=False, help="Also list the dictionary.")
@json_option
def show_cmd(profile: str, product: str | None, revision: str | None, objects: bool, as_json: bool) -> None:
    """Show PROFILE: identity, family limits, default PDO mappings and assignment (and its dictionary)."""
    from ecattool.sim.describe import describe_drive

    drive = _sim_drive(profile=profile, product=product, revision=revision)
    info = describe_drive(drive, objects)
    if as_json:
        print_json(info)
        return
    _render_show(drive.device, info)


def _sim_drive(*, source: str | None = None, profile: str | None = None, product: str | None = None,
               revision: str | None = None, select: str | None = None, policy: str = "exact") -> Drive:
    """The simulated drive of the one-slave machine the device flags build (a project entry's device and rules;
    SOURCE: an ESI/EDS file, else a built-in profile name)."""
    from ecattool.project.machine import Machine
    from ecattool.sim.drive import Drive

    slave = Machine.from_device_flags(source=source, profile=profile, product=product, revision=revision,
                                      select=select, policy=policy).slaves[0]
    return Drive.from_device(slave.require_device(), slave.rules)


def _render_show(dev: Device, info: dict[str, Any]) -> None:
    """The identity line, the limits, the PDOs after reset and (where described) the dictionary."""
    c = console()
    c.print(f"{info['profile']}: {dev.name or dev.type_name}  vendor 0x{dev.vendor_id:08X}  "
            f"product 0x{dev.product_code:08X}  revision 0x{dev.revision:08X}")
    c.print("limits: " + ", ".join(f"{k}={v}" for k, v in info["rules"].items() if v not in (None, [])))
    t = table("PDOs after reset", ["dir", "index", "name", "assigned", "bits", "entries"])
    for p in info["pdos"]:
        t.add_row(p["direction"], f"0x{p['index']:04X}", p["name"], "yes" if p["assigned"] else "", str(p["bits"]),
                  " ".join(p["entries"]))
    c.print(t)
    if "objects" in info:
        t = table("Dictionary", ["index", "sub", "name", "type", "access", "map", "default"])
        for o in info["objects"]:
            for e in o["entries"]:
                t.add_row(f"0x{o['index']:04X}", str(e["subindex"]), e["name"] or o["name"], e["type"], e["access"],
                          e["pdo_mapping"], e["default"] or "")
        c.print(t)


def _value_text(drive: Drive, ln: Line) -> tuple[str, bool]:
    """A value read or written, as people read it, and whether it was decoded from the raw bytes: ``= 1600
    (0x0640): switch on disabled, remote, target reached — SWITCH_ON_DISABLED`` (decimal and hex by the entry's
    data type; the statusword's bits and state named)."""
    plain = f" = {ln.value!r}" if ln.value is not None else ""
    if not ln.data or not (isinstance(ln.value, int) or (ln.value is None and ln.op == "write")):
        return plain, False
    from ecattool.od.display import value_text
    from ecattool.od.numbers import parse_address
    from ecattool.sim.cia402 import decode_statusword

    try:
        index, sub = parse_address(ln.target)
        raw = bytes.fromhex(ln.data)
    except (ValueError, EcatToolError):
        return plain, False
    entry = drive.device.dictionary.entry(index, sub)
    text = value_text(raw, entry.datatype if entry else None, entry.bit_size if entry else None, index,
                      entry.unit if entry else "")
    if index == 0x6041 and isinstance(ln.value, int):
        text += f" — {decode_statusword(ln.value).value}"
    return f" = {text}", True


@sim.command("run", epilog="""\b
Examples:
  ecattool sim run technosoft-ipos rxpdo3.yaml
  ecattool sim run elmo.xml steps.json --device 2 --json
  ecattool sim run hdt steps.yaml -o transcript.json --json
\b
Script (YAML or JSON list):
  - state: PREOP
  - write: "1C12:00"
    value: 0
  - read: "6041:00"
  - write: "6041:00"
    value: 1
    expect_abort: 0x06010002
  - state: OP
    expect_al_status: 0x0011""")
@click.argument("source")
@click.argument("script", type=InputFile())
@click.option("--product", help="Model of a built-in family.")
@click.option("--revision", help="Firmware revision of a built-in family.")
@click.option("--device", "selector", help="Device selector when SOURCE is an ESI file with several devices.")
@policy_option
@output_option()
@json_option
def run_cmd(source: str, script: str, product: str | None, revision: str | None, selector: str | None, policy: str,
            output: str | None, as_json: bool) -> None:
    """Run SCRIPT (SDO reads/writes, state requests, cycles) on a simulated drive and print the transcript.

    SOURCE is a built-in profile name or an ESI (or CANopen EDS) file, as in `sim serve` (a --target
    elsewhere is where a command runs: sim or pysoem:IF). Exits 1 at the first unexpected abort, timeout or
    refused state change.
    """
    from ecattool.sim.script import load_script, run_script

    drive = _sim_drive(source=source, product=product, revision=revision, select=selector, policy=policy)
    steps, locations = load_script(script)
    tr = run_script(drive, steps, locations, script, Path(script).parent)
    if as_json:
        write_output(output, dump_json(tr.to_json()) + "\n", [script, source])
    else:
        write_output(output, _transcript_text(drive, tr), [script, source])
    failure = tr.failure
    if failure is not None:
        code = f" 0x{failure.code:08X}" if failure.code is not None else ""
        raise TargetError(f"step {failure.step} ({failure.op} {failure.target}) ended with {failure.result}{code}"
                          + (f": {failure.detail}" if failure.detail else ""), Location(script, failure.line))


def _transcript_text(drive: Drive, tr: Transcript) -> str:
    """The transcript, one line a step: ok/ERR, step, operation, object, result, code, value as people read it."""
    lines = []
    for ln in tr.lines:
        mark = "ok " if ln.expected else "ERR"
        code = f" 0x{ln.code:08X}" if ln.code is not None and ln.code > 0xFFFF else (
            f" 0x{ln.code:04X}" if ln.code is not None else "")
        val, decoded = _value_text(drive, ln)
        data = f" [{ln.data}]" if ln.data and not decoded else ""
        lines.append(f"{mark} {ln.step:3d} {ln.op:8s} {ln.target:10s} {ln.result}{code}{val}{data}"
                     + (f"  {ln.detail}" if ln.detail else ""))
    return "\n".join(lines) + "\n"


@sim.command("serve", epilog="""\b
Examples:
  ecattool sim serve samples/hdt/project.yaml --iface ecat1
  ecattool sim serve hdt --product tomcat technosoft-ipos --iface ecat1 --json
  ecattool sim serve drive.xml --device 2 --iface ecat1
  ecattool sim serve samples/hdt/project.yaml --list --json
  ecattool sim serve hdt hdt hdt hdt hdt hdt hdt hdt hdt hdt hdt hdt hdt hdt hdt hdt --iface ecat1 --workers 2
\b
Run it inside a private network namespace with a veth pair (never on the host's network):
  unshare -n sh -c '
    ip link add ecat0 type veth peer name ecat1
    ip link set ecat0 up; ip link set ecat1 up
    ecattool sim serve samples/hdt/project.yaml --iface ecat1 > serve.log & serve=$!
    trap "kill $serve; wait $serve" EXIT
    until grep -q serving serve.log; do kill -0 $serve || exit 1; sleep 0.1; done
    ecattool commission samples/hdt/project.yaml --target pysoem:ecat0'
  (the trap stops the server however the commissioning ends; see docs/virtual-bus.md)""")
@click.argument("sources", nargs=-1, required=True)
@click.option("--iface", help="Network interface to serve on (raw Ethernet, EtherType 0x88A4).")
@click.option("--product", help="Model of a built-in family named as a SOURCE.")
@click.option("--revision", help="Firmware revision of a built-in family named as a SOURCE.")
@click.option("--device", "selector", help="Device selector when a SOURCE is an ESI file with several devices.")
@click.option("--frames", type=click.IntRange(min=1), default=None,
              help="Stop after this many frames (default: until SIGINT/SIGTERM).")
@click.option("--list", "list_only", is_flag=True, help="Print the slaves in bus order and exit (no interface).")
@click.option("--workers", type=click.IntRange(min=1), default=None,
              help="Processes serving the line, each a segment of consecutive slaves (default: one per 16 drives, "
                   "at most one per core).")
@click.option("--allow-errors", is_flag=True, help="Serve a project even when lint reports errors for it.")
@click.option("--misbehave", metavar="NAME", hidden=True,
              help="Test hook: every slave misbehaves as NAME (ecattool.sim.bus.misbehave; one process serves).")
@json_option
def serve_cmd(sources: tuple[str, ...], iface: str | None, product: str | None, revision: str | None,
              selector: str | None, frames: int | None, list_only: bool, workers: int | None, allow_errors: bool,
              misbehave: str | None, as_json: bool) -> None:
    """Serve simulated drives as EtherCAT slaves on a network interface, for a real master (SOEM/pysoem).

    SOURCES, in bus order: a project file (every drive of the project, in its bus order), a built-in profile
    name, or an ESI file. Each drive sits behind an ESC model whose SII is what 'ecattool sii build' makes, with
    the sync managers that SII gives (a coupler or a digital terminal without a mailbox too). A slave the ESC
    model cannot serve is refused before serving starts, in one line naming it (exit 1). Prints one line when
    the slaves are ready; stops cleanly on SIGINT/SIGTERM. See docs/virtual-bus.md.
    """
    from ecattool.project.bus import served_devices
    from ecattool.sim.bus.serve import serve, virtual_slaves

    if iface is None and not list_only:
        raise click.UsageError("--iface is required (or --list to only show the slaves)")
    slaves = virtual_slaves(served_devices(sources, product=product, revision=revision, selector=selector,
                                           allow_errors=allow_errors))
    if list_only:
        _render_slaves(slaves, as_json)
        return
    assert iface is not None
    fault = None
    if misbehave is not None:  # the hostile-slave test's switch (tests/wire/test_wire_hostile_slave.py)
        from ecattool.sim.bus.misbehave import apply

        fault, workers = apply(misbehave, slaves), 1
    serve(slaves, iface, _ready_line(slaves, iface, as_json), frames, fault=fault, workers=workers)


def _render_slaves(slaves: list[Served], as_json: bool) -> None:
    """``sim serve --list``: the slaves in bus order."""
    if as_json:
        print_json([s.describe() for s in slaves])
        return
    t = table(None, ["position", "name", "vendor", "product code", "revision"])
    for i, s in enumerate(slaves):
        d = s.describe()
        t.add_row(str(i), s.name, f"0x{d['vendor_id']:08X}", f"0x{d['product_code']:08X}", f"0x{d['revision']:08X}")
    console().print(t)


def _ready_line(slaves: list[Served], iface: str, as_json: bool) -> Callable[[], None]:
    """What the server prints once its slaves are ready: one line, flushed (whoever started it waits for it)."""
    def ready() -> None:
        if as_json:
            import json

            click.echo(json.dumps({"iface": iface, "slaves": [s.describe() for s in slaves]}))
        else:
            names = ", ".join(f"{i}: {s.name}" for i, s in enumerate(slaves))
            click.echo(f"serving {len(slaves)} slave{'s' if len(slaves) != 1 else ''} on {iface} ({names})")
        sys.stdout.flush()

    return ready
