"""``ecattool esi``: list, show and validate ESI device description files."""

from __future__ import annotations

import os
from typing import TYPE_CHECKING, Any

import click

from ecattool.cli.common import console, json_option, output_option, print_json, table, write_output
from ecattool.cli.paths import InputFile

if TYPE_CHECKING:
    from rich.console import Console

    from ecattool.esi.model import Device, EsiFile
    from ecattool.findings import Finding
    from ecattool.od.model import Entry, OdObject

_FILE = click.argument("file", type=InputFile(allow_dash=True))


def _load(file: str, lazy: bool = False) -> EsiFile:
    """Load FILE, or standard input for '-' (``lazy``: devices built when selected)."""
    from ecattool.esi import load, load_bytes

    if file == "-":
        from ecattool.fileio import read_stdin
        from ecattool.xmlsafe import MAX_XML_BYTES

        return load_bytes(read_stdin(MAX_XML_BYTES), "<stdin>", lazy=lazy)
    return load(file, lazy=lazy)


def _hex(v: int | None, width: int = 8) -> str:
    return "" if v is None else f"0x{v:0{width}X}"


@click.group("esi", epilog="""\b
Examples:
  ecattool esi devices samples/esi/etg2001_cia402.xml
  ecattool esi show beckhoff_EL1xxx.xml --device EL1008 --pdos
  ecattool esi validate drive.xml --schema-dir ETG/EtherCATInfo_v1.17
  ecattool esi export technosoft-ipos --revision F515K -o ipos.xml""")
def esi() -> None:
    """Read, show, validate and write ESI (EtherCAT Slave Information) XML files.

    Reads EtherCATInfo, EtherCATModule and EtherCATDict files as vendors ship them (UTF-8 or
    ISO-8859-1, BOM, #x/decimal numbers, many devices and revisions in one file), and CANopen
    EDS/DCF files (told apart by content) into the same device model.
    """


# --------------------------------------------------------------------------------------------
# devices
# --------------------------------------------------------------------------------------------
@esi.command("devices", epilog="""\b
Examples:
  ecattool esi devices samples/esi/etg2001_cia402.xml
  ecattool esi devices beckhoff_EL1xxx.xml --json
  ecattool esi devices technosoft_iPOS.D.v1.04.eds
  curl -s https://example.com/drive.xml | ecattool esi devices -""")
@_FILE
@json_option
def devices_cmd(file: str, as_json: bool) -> None:
    """List the devices of FILE: type, product code, revision, PDO and object counts.

    A device that cannot be read is left out with a one-line error naming its file and line (exit status 1);
    the other devices are listed. Warnings go to standard error; with --json each device also lists its own
    under "warnings".
    """
    from ecattool.esi import device_findings, file_findings
    from ecattool.esi.describe import device_summary

    doc = _load(file)
    rows = [device_summary(d, i) for i, d in enumerate(doc.devices)]
    for r, d in zip(rows, doc.devices):
        r["warnings"] = [w.to_json() for w in device_findings(doc, d)]
    skipped = any(w.rule in ("esi-device-skipped", "esi-module-skipped") for w in doc.warnings)
    if as_json:
        print_json(rows)
        for w in file_findings(doc):
            click.echo(str(w), err=True)
        if skipped:
            raise click.exceptions.Exit(1)
        return
    _render_devices("<stdin>" if file == "-" else file, doc, rows)
    _echo_warnings(doc.warnings)
    if skipped:
        raise click.exceptions.Exit(1)


def _render_devices(name: str, doc: EsiFile, rows: list[dict[str, Any]]) -> None:
    """The devices of the file ``name`` as a table, titled with the vendor and, for a file that is not an
    EtherCATInfo, what it holds."""
    title = f"{name}: {len(rows)} device(s), vendor {_hex(doc.vendor_id)} {doc.vendor_name}".rstrip()
    if doc.root in ("EDS", "DCF"):
        title += f" [CANopen {doc.root}]"
    elif doc.root != "EtherCATInfo":
        title += f" [{doc.root}: {len(doc.modules)} module(s)"
        title += f", {len(doc.dictionary)} object(s)]" if doc.dictionary is not None else "]"
    t = table(title, ["#", "type", "product", "revision", "RxPDO", "TxPDO", "objects", "mailbox", "name"],
              optional=("RxPDO", "TxPDO", "objects", "mailbox"))
    for r in rows:
        t.add_row(str(r["index"]), r["type"], _hex(r["product_code"]), _hex(r["revision"]), str(r["rx_pdo_count"]),
                  str(r["tx_pdo_count"]), str(r["object_count"]), ",".join(r["protocols"]), r["name"])
    console().print(t)


# --------------------------------------------------------------------------------------------
# show
# --------------------------------------------------------------------------------------------
def _render_pdos(con: Console, dev: Device) -> None:
    groups = [("RxPDOs (outputs)", dev.rx_pdos), ("TxPDOs (inputs)", dev.tx_pdos)]
    if not dev.rx_pdos and not dev.tx_pdos and dev.modules:
        groups = []
    for m in dev.modules:
        ident = _hex(m.ident) if m.ident is not None else "-"
        groups.append((f"Module {m.type_name} (ident {ident}): RxPDOs", m.rx_pdos))
        groups.append((f"Module {m.type_name} (ident {ident}): TxPDOs", m.tx_pdos))
    for label, pdos in groups:
        t = table(f"{label}: {len(pdos)}", ["PDO", "entry", "bits", "type", "name", "flags"])
        for p in pdos:
            flags = " ".join(f for f, on in (("fixed", p.fixed), ("mandatory", p.mandatory), ("virtual", p.virtual)) if on)
            sm = f"Sm{p.sm}" if p.sm is not None else "unassigned"
            excl = (" excludes " + ",".join(_hex(x, 4) for x in p.excludes)) if p.excludes else ""
            t.add_row(_hex(p.index, 4), "", str(p.bit_size), "", p.name, f"{sm} {flags}{excl}".strip())
            for e in p.entries:
                where = "gap" if e.is_gap else f"{e.index:04X}:{e.subindex:02X}"
                t.add_row("", where, str(e.bit_len), e.data_type, e.name, "")
        con.print(t)


def _default(o: OdObject, e: Entry) -> str:
    """An entry's ESI default as a value (``10000 (0x2710)``), decoded by its data type; --json keeps the hex."""
    from ecattool.od.display import value_text

    return value_text(e.default, e.datatype, e.bit_size, o.index, e.unit) if e.default is not None else ""


def _render_objects(con: Console, dev: Device) -> None:
    od = dev.dictionary
    t = table(f"Objects: {len(od)}", ["index", "sub", "name", "type", "bits", "access", "map", "default"])
    for o in od:
        t.add_row(_hex(o.index, 4), "", o.name, f"{o.object_code.value} {o.type_name}".strip(), str(o.bit_size), "", "", "")
        if o.object_code.value == "VAR" and len(o.entries) == 1:
            e = next(iter(o))
            t.add_row("", "00", "", e.type_name, str(e.bit_size), e.access.text, e.pdo_mapping, _default(o, e))
            continue
        for e in o:
            t.add_row("", f"{e.subindex:02X}", e.name, e.type_name, str(e.bit_size), e.access.text, e.pdo_mapping,
                      _default(o, e))
    con.print(t)


def _render_sm(con: Console, dev: Device) -> None:
    t = table("Sync managers", ["SM", "kind", "start", "default", "min", "max", "control", "enable"])
    for s in dev.sync_managers:
        t.add_row(str(s.number), s.kind or "(unused)", _hex(s.start_address, 4), str(s.default_size or ""),
                  str(s.min_size or ""), str(s.max_size or ""), _hex(s.control_byte, 2),
                  ("yes" if s.enable else "no") + (f" ({_hex(s.enable_byte, 2)})" if (s.enable_byte or 0) > 1 else ""))
    con.print(t)
    if dev.fmmus:
        con.print("FMMUs: " + ", ".join(f.kind or "(unused)" for f in dev.fmmus))


def _render_dc(con: Console, dev: Device) -> None:
    t = table("DC op modes", ["name", "AssignActivate", "CycleTimeSync0", "ShiftTimeSync0", "CycleTimeSync1", "description"])
    for m in dev.dc_opmodes:
        def fmt(v: int | None, f: int | None) -> str:
            return "" if v is None else (f"{v} (factor {f})" if f is not None else str(v))
        t.add_row(m.name, _hex(m.assign_activate, 4), fmt(m.cycle_time_sync0, m.cycle_time_sync0_factor),
                  fmt(m.shift_time_sync0, m.shift_time_sync0_factor), fmt(m.cycle_time_sync1, m.cycle_time_sync1_factor),
                  m.desc)
    con.print(t)


def _render_init(con: Console, dev: Device) -> None:
    from ecattool.esi.describe import init_cmds
    from ecattool.od.display import value_text

    t = table("Init commands", ["transition", "protocol", "address", "data", "CA", "comment"])
    for c in init_cmds(dev):
        addr = f"IDN {c.index}" if c.protocol == "SoE" else f"{c.index:04X}:{c.subindex:02X}"
        data = c.data.hex(" ") if c.protocol == "SoE" or c.complete_access else value_text(c.data, index=c.index)
        t.add_row(",".join(c.transitions), c.protocol, addr, data, "yes" if c.complete_access else "", c.comment)
    con.print(t)


@esi.command("show", epilog="""\b
Examples:
  ecattool esi show samples/esi/etg2001_cia402.xml --pdos
  ecattool esi show beckhoff_EL1xxx.xml --device EL1008 --policy newest --objects
  ecattool esi show elmo.xml --device 0x00030924:0x00010420 --sm --dc --init-cmds
  ecattool esi show beckhoff_EL1xxx.xml --device 3 --json""")
@_FILE
@click.option("--device", "selector", help="Type name, product[:revision] (any notation) or list index.")
@click.option("--policy", type=click.Choice(["exact", "newest-not-newer", "newest"]), default="exact",
              show_default=True, help="Which revision to take when several match.")
@click.option("--pdos", is_flag=True, help="Show the PDOs and their entries.")
@click.option("--objects", is_flag=True, help="Show the object dictionary.")
@click.option("--sm", is_flag=True, help="Show sync managers and FMMUs.")
@click.option("--dc", is_flag=True, help="Show distributed-clock op modes.")
@click.option("--init-cmds", "init_cmds", is_flag=True, help="Show mailbox init commands.")
@json_option
def show_cmd(file: str, selector: str | None, policy: str, pdos: bool, objects: bool, sm: bool, dc: bool,
             init_cmds: bool, as_json: bool) -> None:
    """Show one device of FILE: identity and summary, or the chosen tables."""
    from ecattool.esi import select_index
    from ecattool.esi.describe import show_document

    doc = _load(file, lazy=True)
    index, dev = select_index(doc, selector, policy)
    len(dev.dictionary)  # the summary counts the objects: built now, so that its warnings are listed
    # a lazy load built only this device: the file's findings are its own and the file-level ones
    warnings = list(doc.warnings)
    if as_json:
        print_json(show_document(dev, index, warnings, pdos=pdos, objects=objects, sm=sm, dc=dc, init=init_cmds))
        return
    _echo_warnings(warnings)
    _render_show(dev, pdos=pdos, objects=objects, sm=sm, dc=dc, init=init_cmds)


def _render_show(dev: Device, *, pdos: bool, objects: bool, sm: bool, dc: bool, init: bool) -> None:
    """The identity and summary, then the sections asked for (none asked for: sync managers and PDOs)."""
    con = console()
    _render_identity(con, dev)
    if not (pdos or objects or sm or dc or init):
        sm = pdos = True
    for shown, render in ((sm, _render_sm), (pdos, _render_pdos), (objects, _render_objects), (dc, _render_dc),
                          (init, _render_init)):
        if shown:
            render(con, dev)


def _echo_warnings(warnings: list[Finding]) -> None:
    """The first 20 warnings on standard error, and how many more there are."""
    for w in warnings[:20]:
        click.echo(str(w), err=True)
    if len(warnings) > 20:
        click.echo(f"… and {len(warnings) - 20} more warnings (ecattool esi validate lists all)", err=True)


def _render_identity(con: Console, dev: Device) -> None:
    con.print(f"{dev.type_name}  {dev.name}")
    con.print(f"  {dev.identity}   group {dev.group_type or '-'}   profile {dev.profile_no or '-'}")
    proto = ",".join(dev.mailbox.protocols) if dev.mailbox else "none"
    con.print(f"  mailbox {proto}   RxPDOs {len(dev.rx_pdos)}   TxPDOs {len(dev.tx_pdos)}   objects {len(dev.dictionary)}"
              f"   DC op modes {len(dev.dc_opmodes)}   slots {len(dev.slots)}   modules {len(dev.modules)}")
    if dev.location:
        con.print(f"  defined at {dev.location}")


# --------------------------------------------------------------------------------------------
# validate
# --------------------------------------------------------------------------------------------
@esi.command("validate", epilog="""\b
Examples:
  ecattool esi validate samples/esi/etg2001_cia402.xml
  ecattool esi validate drive.xml --schema-dir ETG/EtherCATInfo_v1.17 --json

\b
ecattool does not ship ETG's schema files; point --schema-dir at a directory with EtherCATInfo.xsd
(EtherCATModule.xsd / EtherCATDict.xsd for those roots) and EtherCATBase.xsd. Exit status 1 on errors.""")
@click.argument("file", type=InputFile())  # a path: DictionaryFile/InfoReference are resolved beside it
@click.option("--schema-dir", type=click.Path(file_okay=False, exists=True),
              help="Directory with the ETG XSD files (chosen by the root element).")
@click.option("--strict", is_flag=True, help="Fail on warnings too.")
@json_option
def validate_cmd(file: str, schema_dir: str | None, strict: bool, as_json: bool) -> None:
    """Validate FILE against the ETG schemas (optional) and ecattool's structural checks."""
    from ecattool.esi import validate
    from ecattool.findings import has_errors

    if file == "-":
        raise click.UsageError("validate reads a file path (DictionaryFile/InfoReference are resolved beside it)")
    findings = validate(file, schema_dir)
    failed = has_errors(findings, strict)
    if as_json:
        print_json({"file": file, "schema_dir": schema_dir, "ok": not failed,
                    "findings": [f.to_json() for f in findings]})
    else:
        for f in findings:
            click.echo(str(f))
        n_err = sum(1 for f in findings if f.severity.value == "error")
        n_warn = sum(1 for f in findings if f.severity.value == "warning")
        checked = "schema and structure" if schema_dir else "structure (no --schema-dir: XSD not checked)"
        click.echo(f"{file}: {checked}: {n_err} error(s), {n_warn} warning(s)")
    if failed:
        raise click.exceptions.Exit(1)


# --------------------------------------------------------------------------------------------
# export
# --------------------------------------------------------------------------------------------
@esi.command("export", epilog="""\b
Examples:
  ecattool esi export technosoft-ipos -o ipos.xml
  ecattool esi export technosoft-ipos --product ipos4808-bx-cat --revision F515I -o ipos4808.xml
  ecattool esi export controltechniques --product digitax-st --revision 01.02.00 -o digitax.xml
  ecattool esi export hdt --product dgfox -o - | ecattool esi devices -
  ecattool esi export technosoft_iPOS.D.v1.04.eds -o ipos_from_eds.xml

\b
SOURCE is a built-in profile name, or a device file (a CANopen EDS/DCF, or an ESI with --device) when a
file of that name exists. The ESI validates against the ETG.2000 schemas v1.14 and v1.17 and reads back to
the same device model (docs/esi.md, "Writing an ESI"); `ecattool sii build ipos.xml -o ipos.bin` makes its
EEPROM image.""")
@click.argument("source", metavar="SOURCE")
@click.option("--product", help="Model of the family (ecattool sim profiles lists them; default the first).")
@click.option("--revision", help="Firmware revision: Technosoft F515K/0x3531354B, Control Techniques 01.02.00.")
@click.option("--device", "selector", help="Device of a SOURCE file with several: type name, product[:revision] "
              "or list index.")
@output_option(required=True)
def export_cmd(source: str, product: str | None, revision: str | None, selector: str | None, output: str) -> None:
    """Write an ESI file for a built-in drive family (technosoft-ipos, hdt, controltechniques) or an EDS."""
    from ecattool import profiles
    from ecattool.esi.export import device_to_esi

    if os.path.isfile(source):
        if product or revision:
            raise click.UsageError("--product/--revision choose a built-in profile's model; for a file use --device")
        from ecattool.esi import load, select

        doc = load(source, lazy=True)
        device = select(doc, selector)
        write_output(output, device_to_esi(device, vendor_name=doc.vendor_name), (source,))
        return
    if selector:
        raise click.UsageError(f"--device selects a device of a file, and there is no file {source!r}")
    device = profiles.load(source, product=product, revision=revision)
    family = profiles.family_of(device)
    vendor = next((i.vendor_name for i in profiles.list_profiles() if i.name == family), "")
    write_output(output, device_to_esi(device, vendor_name=vendor))
