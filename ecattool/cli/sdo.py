"""``ecattool sdo``: read and write objects of a live slave, typed by its dictionary."""

from __future__ import annotations

from typing import Any

import click

from ecattool.cli.common import (
    console,
    dump_json,
    json_option,
    output_option,
    print_json,
    table,
    write_output,
)
from ecattool.cli.online import (
    device_option,
    library_option,
    load_device,
    load_library,
    open_live,
    slave_option,
    target_option,
)
from ecattool.cli.paths import InputFile
from ecattool.errors import InputError, TargetError, did_you_mean
from ecattool.od.numbers import parse_address
from ecattool.online.dictionary import standard_typed, typed
from ecattool.online.objects import diff_snapshots, load_snapshot, read_value, write_value
from ecattool.online.objects import dump as do_dump


def _address(text: str) -> tuple[int, int] | None:
    """``text`` as an object address (6060:00, 0x6060:0, 6060h), or None when it is not one (a name, then)."""
    try:
        return parse_address(text)
    except InputError:
        return None


def _object(text: str, address: tuple[int, int] | None, t: Any, slave: int) -> tuple[int, int]:
    """The object ``text`` names: its address, or a name found in the slave's dictionary ``t``."""
    if address is not None:
        return address
    found = t.dictionary.find(text)
    if found is not None:
        return found  # type: ignore[no-any-return]
    if not len(t.dictionary):
        raise InputError(f"{text!r} is not an object address (write 6060:00 or 0x6060:0), and slave {slave} has no "
                         "dictionary to find it by name in (give --device or --library)")
    names = [o.name for o in t.dictionary]
    raise InputError(f"{text!r} is neither an object address (6060:00, 0x6060:0) nor the name of an object in slave "
                     f"{slave}'s dictionary ({t.source}){did_you_mean(text, names)}")


def _typed(slave: Any, library: str | None, device: Any, sdo_info: bool = True) -> Any:
    """The dictionary typing ``slave``'s objects: ``device`` (loaded by load_device), else the library, the family,
    the slave's SDO Information."""
    return typed(slave, load_library(library), device, sdo_info=sdo_info)


@click.group(epilog="""\b
Examples:
  ecattool sdo read 0x6060:00 --target pysoem:eth0
  ecattool sdo write 0x6081:00 50000 --target pysoem:eth0 --slave 1
  ecattool sdo dump --target pysoem:eth0 -o axis1.dict.json
  ecattool sdo diff axis1-old.dict.json axis1.dict.json""")
def sdo() -> None:
    """Read and write a live slave's objects over SDO, typed by its dictionary (ESI, EDS, built-in family or
    the slave's SDO Information service); abort codes are named."""


@sdo.command(epilog="""\b
Examples:
  ecattool sdo read 0x6060:00 --target pysoem:eth0
  ecattool sdo read 0x1018:01 --target kickcat:eth0 --json
  ecattool sdo read 0x6064:00 --target sim:technosoft-ipos
  ecattool sdo read controlword --target pysoem:eth0 --device drive.xml""")
@click.argument("address")
@target_option()
@slave_option
@library_option
@device_option
@json_option
def read(address: str, target: str, slave: int, library: str | None, device: str | None, as_json: bool) -> None:
    """Read one object (INDEX:SUB, or its name in the slave's dictionary: controlword) and show its value decoded
    by its data type; without a dictionary, as raw bytes."""
    addr = _address(address)
    # a CiA-301 object by its address (1018h:01 …) is typed by the standard: no identity, family or SDO Information
    quick = standard_typed(*addr) if addr is not None and device is None and library is None else None
    with open_live(target, dev := load_device(device)) as live:
        s = live.slave(slave)
        t = quick or _typed(s, library, dev)  # the SDO Information service is asked at most once
        index, sub = _object(address, addr, t, slave)
        v = read_value(s, t, index, sub)
    if as_json:
        print_json({**v.to_json(), "dictionary": t.source})
    else:
        name = f" {v.name}" if v.name else ""
        kind = f" ({v.type_name})" if v.type_name else ""
        click.echo(f"0x{index:04X}:{sub:02X}{name}{kind} = {v.value!r} [hex {(v.data or b'').hex()}]")


@sdo.command(epilog="""\b
Examples:
  ecattool sdo write 0x6060:00 1 --target pysoem:eth0
  ecattool sdo write 0x2000:00 hex:0A0B0C0D --target pysoem:eth0 --slave 2""")
@click.argument("address")
@click.argument("value")
@target_option()
@slave_option
@library_option
@device_option
@json_option
def write(address: str, value: str, target: str, slave: int, library: str | None, device: str | None,
          as_json: bool) -> None:
    """Write one object: VALUE is encoded by the object's data type (range checked), or given as hex:BYTES."""
    addr = _address(address)
    with open_live(target, dev := load_device(device)) as live:
        s = live.slave(slave)
        t = _typed(s, library, dev)
        index, sub = _object(address, addr, t, slave)
        data = write_value(s, t, index, sub, value)
    if as_json:
        print_json({"address": f"0x{index:04X}:{sub:02X}", "hex": data.hex(), "dictionary": t.source})
    else:
        click.echo(f"0x{index:04X}:{sub:02X} := {data.hex()}")


@sdo.command(epilog="""\b
Examples:
  ecattool sdo info --target pysoem:eth0
  ecattool sdo info --target sim:hdt --json""")
@target_option()
@slave_option
@library_option
@device_option
@json_option
def info(target: str, slave: int, library: str | None, device: str | None, as_json: bool) -> None:
    """The slave's dictionary (objects, entries, types, access) and where it comes from."""
    with open_live(target, dev := load_device(device)) as live:
        t = _typed(live.slave(slave), library, dev)
    if not len(t.dictionary):
        why = t.sdo_info_error or f"slave {slave} offers no SDO Information"
        raise TargetError(f"{why}; and no --device, --library or built-in family describes it: its objects can still "
                          "be read as raw bytes, 'ecattool sdo read INDEX:SUB'")
    rows = [{"address": f"0x{o.index:04X}:{e.subindex:02X}", "object": o.name, "name": e.name,
             "type": e.type_name, "bits": e.bit_size,
             "read": sorted(s.value for s in e.access.read), "write": sorted(s.value for s in e.access.write),
             "pdo": e.pdo_mapping} for o in t.dictionary for e in o]
    if as_json:
        print_json({"dictionary": t.source, "entries": rows})
        return
    tab = table(f"slave {slave}: {len(rows)} entries (dictionary: {t.source})",
                ["address", "name", "type", "bits", "write in", "pdo"])
    for r in rows:
        tab.add_row(r["address"], r["name"] or r["object"], r["type"], str(r["bits"]), ",".join(r["write"]), r["pdo"])
    console().print(tab)


@sdo.command(epilog="""\b
Examples:
  ecattool sdo dump --target pysoem:eth0 --slave 1 -o axis2.dict.json
  ecattool sdo dump --target sim:technosoft-ipos""")
@target_option()
@slave_option
@library_option
@device_option
@output_option()
def dump(target: str, slave: int, library: str | None, device: str | None, output: str | None) -> None:
    """Read every readable object of the slave's dictionary into a JSON snapshot (values, or the abort code
    where the slave refuses one). Written only when the whole bus read succeeded."""
    with open_live(target, dev := load_device(device)) as live:
        s = live.slave(slave)
        snapshot = do_dump(s, _typed(s, library, dev), target)
    write_output(output, dump_json(snapshot) + "\n")


@sdo.command("diff", epilog="""\b
Examples:
  ecattool sdo diff axis2-2026-01.dict.json axis2-2026-11.dict.json
  ecattool sdo diff before.dict.json after.dict.json --json""")
@click.argument("a", type=InputFile())
@click.argument("b", type=InputFile())
@json_option
def diff(a: str, b: str, as_json: bool) -> None:
    """Compare two dictionary snapshots ('sdo dump', 'backup'): the objects whose value or abort differs, and
    those only one of them has. Exit status 1 when they differ."""
    sa, sb = load_snapshot(a), load_snapshot(b)
    diffs = diff_snapshots(sa, sb)
    if as_json:
        print_json({"a": a, "b": b, "identical": not diffs, "differences": [d.to_json() for d in diffs]})
    else:
        for d in diffs:
            click.echo(str(d))
        click.echo(f"{len(diffs)} difference(s)" if diffs else "no differences")
    raise SystemExit(1 if diffs else 0)
