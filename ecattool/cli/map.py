"""``ecattool map``: check, lay out and program PDO mappings."""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING

import click

from ecattool.cli.common import (
    Decorated,
    console,
    dump_json,
    file_output_option,
    json_option,
    output_option,
    policy_option,
    print_json,
    store_force,
    table,
    write_output,
)
from ecattool.cli.paths import InputFile
from ecattool.cli.vocab import WRITE_FORMATS, AliasedOption
from ecattool.errors import InputError

if TYPE_CHECKING:
    from ecattool.esi.model import Device
    from ecattool.findings import Finding
    from ecattool.pdo import Mapping
    from ecattool.pdo.layout import Layout as ProcessLayout
    from ecattool.startup import SlaveConfig, StartupList

_EXAMPLES = """\b
Examples:
  ecattool map {cmd} --profile technosoft-ipos --rx "0x1600=controlword,0x607A:00/32"
  ecattool map {cmd} --esi synapticon_Somanet_CiA402-single.xml --tx "0x1A00=statusword,0x6064:00/32"
  ecattool map {cmd} --profile technosoft-ipos --rx "0x1600;0x1601;0x1602=controlword,modes of operation"
  ecattool map {cmd} --esi drive.xml --device EL7211 --mapping mapping.yaml --json
  ecattool map {cmd} --profile technosoft-ipos --product ipos4808-bx-cat --startup ecmc_ecmciPOSXXXX.cmd
  ecattool map sdo --profile hdt --rx "0x1600=controlword,0x607A:00/32" --format twincat -o startup.txt

\b
Mapping syntax: PDOs separated by ';', entries by ','; an entry is 0x6040:00/16, 6040:0/16, an object
name (controlword, "modes of operation"), a raw value 0x60400010, or gap/8. A PDO index alone
(0x1601) assigns that PDO with its device contents. Directions not given keep the device default.
--mapping FILE.yaml holds {{rx: [{{index: 0x1600, entries: [controlword, ...]}}], tx: [...]}}."""


def _device_options(f: Decorated) -> Decorated:
    opts: list[Callable[[Decorated], Decorated]] = [
        click.option("--esi", type=InputFile(), help="ESI file of the device."),
        # without --esi, --device NAME still names a built-in profile, as it did before --profile existed
        click.option("--device", "selector", metavar="SEL",
                     help="Device in the ESI (type name, product[:revision] or list index)."),
        click.option("--profile", help="Built-in drive family (technosoft-ipos, hdt, controltechniques)."),
        click.option("--product", help="Model of the built-in family."),
        click.option("--revision", help="Revision/firmware of the built-in family or ESI device."),
        policy_option,
        click.option("--rx", multiple=True, help="RxPDO assignment and mapping (outputs, SM2, 1C12h)."),
        click.option("--tx", multiple=True, help="TxPDO assignment and mapping (inputs, SM3, 1C13h)."),
        click.option("--mapping", "mapping_file", type=InputFile(allow_dash=True),
                     help="YAML/JSON file with rx/tx PDO lists (or a 'pdo:' section)."),
        click.option("--startup", "startup_file", type=InputFile(),
                     help="A master configuration (ENI, TwinCAT, ecmc, ros2, IgH, JSON/CSV startup list): use the "
                     "mapping its SDOs program (or its declared PDOs)."),
        # --drive as `startup export/convert` spell it; --slave N, its old spelling, still takes the number
        click.option("--drive", "--slave", "drive", metavar="NAME", cls=AliasedOption, aliases=("--slave",),
                     help="Which slave of a --startup file: its name or bus position."),
    ]
    for opt in reversed(opts):
        f = opt(f)
    return f


def _load_device(esi: str | None, selector: str | None, profile: str | None, product: str | None,
                 revision: str | None, policy: str = "exact") -> Device:
    """The device of the one-slave machine the flags build (as a project entry ``device:`` would: the device as
    it runs, default modules in its slots and mapping objects, as lint and the simulator see it)."""
    if esi and profile:
        raise click.UsageError("give either --esi or --profile, not both")
    if not (esi or profile or selector):
        raise click.UsageError("name the device: --esi FILE [--device SEL] or --profile NAME")
    from ecattool.project.machine import Machine

    # without --esi, --device NAME names a built-in profile, as it did before --profile existed
    machine = Machine.from_device_flags(esi=esi, select=selector, policy=policy,
                                        profile=None if esi else profile or selector, product=product,
                                        revision=revision)
    return machine.slaves[0].require_device()


def _load_mapping(device: Device, rx: tuple[str, ...], tx: tuple[str, ...], mapping_file: str | None) -> Mapping:
    from ecattool import pdo

    if mapping_file:
        if rx or tx:
            raise click.UsageError("give the mapping either with --rx/--tx or with --mapping, not both")
        return pdo.Mapping.from_file(mapping_file, device)
    return pdo.Mapping.from_text(rx=list(rx) if rx else None, tx=list(tx) if tx else None, device=device)


def _setup(esi: str | None, selector: str | None, profile: str | None, product: str | None, revision: str | None,
           rx: tuple[str, ...], tx: tuple[str, ...], mapping_file: str | None, startup_file: str | None = None,
           drive: str | None = None, device: Device | None = None,
           policy: str = "exact") -> tuple[Device, Mapping, SlaveConfig | None]:
    """(device, mapping, master configuration or None)."""
    device = device if device is not None else _load_device(esi, selector, profile, product, revision, policy)
    if startup_file:
        if rx or tx or mapping_file:
            raise click.UsageError("give the mapping with one of --rx/--tx, --mapping or --startup")
        from ecattool import pdo
        from ecattool.startup import import_file, select_one

        config = select_one(import_file(startup_file), drive, startup_file)
        return device, pdo.mapping_from_config(config, device), config
    return device, _load_mapping(device, rx, tx, mapping_file), None


@click.group(name="map", epilog="""\b
Examples:
  ecattool map check --profile technosoft-ipos --rx "0x1600=controlword,0x607A:00/32"
  ecattool map layout --esi drive.xml --device EL7211 --mapping mapping.yaml
  ecattool map sdo --profile hdt --rx "0x1600=controlword,0x607A:00/32" --format twincat -o startup.txt""")
def map_() -> None:
    """Check, lay out and program PDO mappings (rule ids PDO0nn, see docs/pdo-mapping.md)."""


@map_.command(epilog=_EXAMPLES.format(cmd="check"))
@_device_options
@click.option("--strict", is_flag=True, help="Exit 1 on warnings too.")
@json_option
def check(esi: str | None, selector: str | None, profile: str | None, product: str | None, revision: str | None,
          policy: str, rx: tuple[str, ...], tx: tuple[str, ...], mapping_file: str | None, startup_file: str | None,
          drive: str | None, strict: bool, as_json: bool) -> None:
    """Check a PDO mapping statically; exit 1 when an error-level finding exists."""
    from ecattool import pdo
    from ecattool.findings import has_errors

    device = _load_device(esi, selector, profile, product, revision, policy)
    try:
        _, mapping, config = _setup(esi, selector, profile, product, revision, rx, tx, mapping_file, startup_file,
                                    drive, device)
    except InputError as exc:
        if not as_json:
            raise
        print_json({"device": device.type_name, "ok": False, "findings": [pdo.input_finding(exc).to_json()]})
        raise SystemExit(1) from None
    findings = pdo.check_config(device, config)[1] if config is not None else pdo.check(device, mapping)
    failed = has_errors(findings, strict=strict)
    _render_check(device, mapping, findings, failed, as_json)
    if failed:
        raise SystemExit(1)


def _render_check(device: Device, mapping: Mapping, findings: list[Finding], failed: bool, as_json: bool) -> None:
    """The findings and the verdict with the process image's sizes (as JSON, or one line each)."""
    from ecattool import pdo

    lay = pdo.layout(device, mapping)
    if as_json:
        print_json({"device": device.type_name, "ok": not failed, "findings": [f.to_json() for f in findings],
                    "outputs_bytes": lay.outputs.byte_size, "inputs_bytes": lay.inputs.byte_size,
                    "mapping": mapping.to_json()})
        return
    for f in findings:
        click.echo(str(f))
    verdict = "FAILED" if failed else "OK"
    click.echo(f"{verdict}: {device.type_name}: outputs {lay.outputs.byte_size} bytes "
               f"({len(mapping.rx)} RxPDOs), inputs {lay.inputs.byte_size} bytes ({len(mapping.tx)} TxPDOs), "
               f"{len(findings)} finding(s)")


@map_.command(epilog=_EXAMPLES.format(cmd="layout") + """
  ecattool map layout --profile technosoft-ipos --rx "0x1600=controlword,0x607A:00/32" --svg layout.svg""")
@_device_options
@json_option
@output_option()
@file_output_option("--svg", "svg", help="Also draw the process image as an SVG diagram into FILE (one box per "
                    "entry with object, name and byte.bit; gaps shown). Needs: pip install 'ecattool[report]'.")
def layout(esi: str | None, selector: str | None, profile: str | None, product: str | None, revision: str | None,
           policy: str, rx: tuple[str, ...], tx: tuple[str, ...], mapping_file: str | None, startup_file: str | None,
           drive: str | None, as_json: bool, output: str | None, svg: str | None) -> None:
    """Show the process image per sync manager: byte.bit offsets, sizes, names and types."""
    from ecattool import pdo

    _svg_prerequisites(svg, as_json or output == "-")
    device, mapping, _ = _setup(esi, selector, profile, product, revision, rx, tx, mapping_file, startup_file, drive,
                                policy=policy)
    # a PDO kept as the device has it is drawn as the slave powers on with it: where the ESI's dictionary and PDO
    # element disagree, the dictionary's (docs/decisions.md, "An ESI that contradicts itself")
    mapping, dictionary_pdos = pdo.powered_on(device, mapping)
    lay = pdo.layout(device, mapping)
    inputs = _inputs(esi, mapping_file, startup_file)
    if svg:
        from ecattool.report import process_image_svg

        write_output(svg, process_image_svg(lay, device.type_name), inputs)
        if svg == "-":
            return
    _render_layout(lay, dictionary_pdos, output, inputs, as_json or output not in (None, "-"))


def _svg_prerequisites(svg: str | None, json_to_stdout: bool) -> None:
    """Before any work: the report extra is there (a missing one is one line, not a half-done run), and the
    diagram and the JSON do not both go to stdout."""
    if svg:
        from ecattool.report import require

        if svg == "-" and json_to_stdout:
            raise click.UsageError("--svg - and the JSON layout cannot both go to stdout")
        require("jinja2")


def _inputs(*paths: str | None) -> tuple[str, ...]:
    """The input files among ``paths`` (an output never replaces one)."""
    return tuple(p for p in paths if p and p != "-")


def _render_layout(lay: ProcessLayout, dictionary_pdos: list[int], output: str | None, inputs: tuple[str, ...],
                   as_json: bool) -> None:
    """The process image as JSON (to ``output``), or a table per sync manager and a note per PDO drawn by the
    dictionary's mapping object."""
    if as_json:
        doc = lay.to_json()
        if dictionary_pdos:  # drawn by the dictionary's mapping object (esi-pdo-default-differs)
            doc["power_on_from_dictionary"] = [f"0x{i:04X}" for i in dictionary_pdos]
        write_output(output, dump_json(doc) + "\n", inputs)
        return
    con = console()
    for img in (lay.outputs, lay.inputs):
        title = (f"{'Outputs' if img.direction.value == 'rx' else 'Inputs'} SM{img.sm if img.sm is not None else '?'}"
                 f" ({img.byte_size} bytes, {img.bit_size} bits)")
        t = table(title, ["offset", "bits", "PDO", "object", "name", "type"])
        for e in img.entries:
            t.add_row(e.offset, str(e.bit_len), f"0x{e.pdo:04X}", "gap" if e.is_gap else f"0x{e.index:04X}:{e.subindex:02X}",
                      e.name, e.type_name)
        con.print(t)
    for index in dictionary_pdos:
        click.echo(f"note: PDO 0x{index:04X} is drawn as the slave powers on with it, by the dictionary's mapping "
                   "object: the ESI's PDO element differs (esi-pdo-default-differs; give its entries to use them)")


@map_.command(epilog=_EXAMPLES.format(cmd="sdo"))
@_device_options
@click.option("--complete-access", is_flag=True, help="Write each object in one complete-access transfer "
              "(only when the device advertises CoE CompleteAccess).")
@click.option("--order", type=click.Choice(["standard", "count-first"]), default="standard", show_default=True,
              help="standard: sub-index 0 = 0, entries, count; count-first: the Control Techniques quick start order.")
@click.option("--transition", default="PS", show_default=True, help="Transition the writes belong to.")
@click.option("--force", is_flag=True, callback=store_force,
              help="Print the sequence even when the mapping has errors; overwrite an existing output file.")
@click.option("--format", "fmt", type=click.Choice(WRITE_FORMATS, case_sensitive=False),
              help="Write the sequence as a startup list for a master (see `ecattool startup`).")
@json_option
@output_option(force=False)
def sdo(esi: str | None, selector: str | None, profile: str | None, product: str | None, revision: str | None,
        policy: str, rx: tuple[str, ...], tx: tuple[str, ...], mapping_file: str | None, startup_file: str | None,
        drive: str | None, complete_access: bool, order: str, transition: str, force: bool, fmt: str | None,
        as_json: bool, output: str | None) -> None:
    """Print the SDO writes that program the mapping, in the order drives require, with exact sizes."""
    from ecattool import pdo

    device, mapping, _ = _setup(esi, selector, profile, product, revision, rx, tx, mapping_file, startup_file, drive,
                                policy=policy)
    _refuse_mapping_errors(pdo.check(device, mapping), force)
    seq = pdo.program(device, mapping, complete_access=complete_access, transition=transition.upper(), order=order)
    coe = device.mailbox.coe if device.mailbox is not None else None
    if complete_access and not (coe is not None and coe.complete_access):
        click.echo(f"note: {device.type_name} does not advertise CoE complete access; writing single sub-indices",
                   err=True)
    inputs = _inputs(esi, mapping_file, startup_file)
    if fmt:
        from ecattool.startup import SlaveConfig, export

        config = SlaveConfig.from_device(device, seq, mapping=mapping)  # with the process data it installs
        write_output(output, export(config, fmt.lower()), inputs)
        return
    _render_sdo(device, seq, output, inputs, as_json or output not in (None, "-"))


def _refuse_mapping_errors(findings: list[Finding], force: bool) -> None:
    """Exit 1 listing the findings when the mapping has errors, unless ``force``."""
    from ecattool.findings import has_errors

    if has_errors(findings) and not force:
        for f in findings:
            click.echo(str(f), err=True)
        click.echo("map sdo: the mapping has errors (above); --force prints the writes anyway", err=True)
        raise SystemExit(1)


def _render_sdo(device: Device, seq: StartupList, output: str | None, inputs: tuple[str, ...],
                as_json: bool) -> None:
    """The writes as JSON rows (to ``output``) or a table."""
    if as_json:
        rows = [{"transition": c.transition, "index": f"0x{c.index:04X}", "subindex": c.subindex,
                 "size": len(c.data), "data": c.data.hex(), "value": f"0x{c.int_value:X}" if not c.complete_access else None,
                 "complete_access": c.complete_access, "comment": c.comment} for c in seq]
        write_output(output, dump_json(rows) + "\n", inputs)
        return
    from ecattool.od.display import int_text

    t = table(f"{device.type_name}: {len(seq)} SDO writes", ["tr", "object", "size", "value", "comment"])
    for c in seq:
        value = c.data.hex(" ") if c.complete_access else int_text(c.int_value, len(c.data))
        t.add_row(c.transition, c.address + (" CA" if c.complete_access else ""), str(len(c.data)), value, c.comment)
    console().print(t)
