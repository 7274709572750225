"""ecattool sii: SII EEPROM images — inspect, check, repair, build from an ESI, compare."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import click

from ecattool.cli.common import (
    check_output,
    console,
    dump_json,
    force_requested,
    json_option,
    output_option,
    parse_int_arg,
    store_force,
    table,
    write_output,
)
from ecattool.cli.online import open_live, reset_bus_option
from ecattool.cli.paths import InputFile
from ecattool.errors import InputError, TargetError

if TYPE_CHECKING:
    from rich.table import Table

    from ecattool.esi.model import Device
    from ecattool.findings import Finding
    from ecattool.sii.model import SiiImage


@click.group("sii", epilog="""\b
Examples:
  ecattool sii build slave.xml --device MySlave -o slave.bin
  ecattool sii check slave.bin
  ecattool sii check slave.xml slave.bin
  ecattool sii info slave.bin --json
  ecattool sii set-alias slave.bin 7 -o slave-alias7.bin
  ecattool sii diff old.bin new.bin""")
def sii() -> None:
    """SII EEPROM images: inspect, check, fix the CRC, set the alias, build from ESI, diff.

    Images are read as binary or Intel HEX (detected by the leading ':'); outputs ending in .hex are
    written as Intel HEX, everything else as binary.
    """


def _stdin(path: str) -> bytes | None:
    """The bytes of standard input when ``path`` is '-' (read once), else None."""
    if path != "-":
        return None
    from ecattool.fileio import read_stdin
    from ecattool.sii.image import MAX_IMAGE_BYTES

    return read_stdin(4 * MAX_IMAGE_BYTES)


def _load(path: str) -> SiiImage:
    from ecattool.sii.image import load

    return load("<stdin>" if path == "-" else path, _stdin(path))


def _write_image(output: str, image: SiiImage, inputs: tuple[str, ...]) -> None:
    data = image.to_bytes()
    if output.lower().endswith((".hex", ".ihex")):
        from ecattool.sii import write_intel_hex

        write_output(output, write_intel_hex(data), inputs)
    else:
        write_output(output, data, inputs)


def _findings_out(findings: list[Finding], as_json: bool, extra: dict[str, Any] | None = None) -> None:
    from ecattool.findings import has_errors

    if as_json:
        click.echo(dump_json({**(extra or {}), "ok": not has_errors(findings),
                              "findings": [f.to_json() for f in findings]}))
    else:
        for f in findings:
            click.echo(str(f))
        n_err = sum(1 for f in findings if f.severity.value == "error")
        n_warn = sum(1 for f in findings if f.severity.value == "warning")
        click.echo(f"{'FAILED' if n_err else 'OK'}: {n_err} error(s), {n_warn} warning(s)")


def _mailbox_text(box: dict[str, int]) -> str:
    """``{'rx_offset': 4096, 'rx_size': 128, …}`` as an engineer writes it: ``out 0x1000 (128 bytes), in 0x1080
    (128 bytes)`` (rx = master to slave = mailbox out, SM0; tx = mailbox in, SM1)."""
    if not any(box.values()):
        return "none"
    return (f"out 0x{box.get('rx_offset', 0):04X} ({box.get('rx_size', 0)} bytes), "
            f"in 0x{box.get('tx_offset', 0):04X} ({box.get('tx_size', 0)} bytes)")


@sii.command("info", epilog="""\b
Examples:
  ecattool sii info slave.bin
  ecattool sii info eeprom.hex --json | jq .categories
  ethercat sii_read -p 0 | ecattool sii info -""")
@click.argument("image", type=InputFile(allow_dash=True))
@json_option
def info(image: str, as_json: bool) -> None:
    """Show the fixed area, every category, strings, SMs, PDOs and DC modes of IMAGE."""
    from ecattool.sii.info import describe

    d = describe(_load(image))
    if as_json:
        click.echo(dump_json(d))
        return
    c = console()
    c.print(_fixed_table(image, d))
    for t in (*_category_tables(d), *_pdo_tables(d)):
        c.print(t)


def _fixed_table(image: str, d: dict[str, Any]) -> Table:
    """The fixed area (identity, mailbox, checksum …) of a described image."""
    t = table(f"SII image {image}", ["field", "value"])
    for key, fmt in (("vendor_id", "0x{:08X}"), ("product_code", "0x{:08X}"), ("revision", "0x{:08X}"),
                     ("serial", "0x{:08X}"), ("station_alias", "{}"), ("config_data", "{}"),
                     ("checksum", "0x{:02X}"), ("crc_ok", "{}"), ("protocols", "{}"), ("mailbox", "{}"),
                     ("bootstrap", "{}"), ("eeprom_bytes", "{}"), ("image_bytes", "{}"), ("version", "{}")):
        v = d[key]
        t.add_row(key, ", ".join(v) if isinstance(v, list) else _mailbox_text(v) if isinstance(v, dict)
                  else fmt.format(v))
    return t


def _category_tables(d: dict[str, Any]) -> list[Table]:
    """The categories, and the strings, general and sync manager categories where the image has them."""
    ct = table("Categories", ["offset", "type", "name", "words"])
    for cat in d["categories"]:
        ct.add_row(f"0x{cat['offset']:04X}", str(cat["type"]), cat["name"] + (" (!)" if cat.get("problem") else ""),
                   str(cat["words"]))
    out = [ct, *_strings_table(d["strings"])]
    if d["general"]:
        gt = table("General", ["field", "value"])
        for k, v in d["general"].items():
            gt.add_row(k, ", ".join(v) if isinstance(v, list) else str(v))
        out.append(gt)
    if d["sync_managers"]:
        smt = table("Sync managers", ["SM", "start", "length", "control", "enable", "type"])
        for i, s in enumerate(d["sync_managers"]):
            smt.add_row(str(i), f"0x{s['start']:04X}", str(s["length"]), f"0x{s['control']:02X}", str(s["enable"]),
                        s["kind"] or "unused")
        out.append(smt)
    return out


def _strings_table(strings: list[str]) -> list[Table]:
    """The strings category, numbered as the other categories refer to them (none where the image has none)."""
    if not strings:
        return []
    st = table("Strings", ["#", "text"])
    for i, s in enumerate(strings, 1):
        st.add_row(str(i), s)
    return [st]


def _pdo_tables(d: dict[str, Any]) -> list[Table]:
    """The TxPDO and RxPDO categories with their entries, and the DC op modes, where the image has them."""
    out = []
    for key, title in (("tx_pdos", "TxPDOs (inputs)"), ("rx_pdos", "RxPDOs (outputs)")):
        if d[key]:
            pt = table(title, ["PDO", "SM", "entry", "bits", "type", "name"])
            for p in d[key]:
                pt.add_row(f"0x{p['index']:04X}", str(p["sm"]), "", str(p["bit_size"]), "", p["name"] or "")
                for e in p["entries"]:
                    pt.add_row("", "", f"0x{e['index']:04X}:{e['subindex']:02X}", str(e["bit_len"]),
                               f"0x{e['data_type']:02X}", e["name"] or "")
            out.append(pt)
    if d["dc_opmodes"]:
        dt = table("DC op modes", ["name", "assign activate", "cycle0", "shift0", "sync0 factor", "sync1 factor"])
        for o in d["dc_opmodes"]:
            dt.add_row(o["name"] or "", f"0x{o['assign_activate']:04X}", str(o["cycle_time0"]), str(o["shift_time0"]),
                       str(o["sync0_cycle_factor"]), str(o["sync1_cycle_factor"]))
        out.append(dt)
    return out


_POLICY = click.option("--policy", type=click.Choice(["exact", "newest-not-newer", "newest"]), default="exact",
                       show_default=True, help="How --device picks a revision when several match.")


def _select(esi_path: str, selector: str | None, image: SiiImage | None = None, policy: str = "exact") -> Device:
    from ecattool.esi import load, select
    from ecattool.esi.reader import LazyEsiFile

    esi = load(esi_path, lazy=True)  # builds only the device chosen (a full load when listing is needed)
    if selector is None and image is not None and isinstance(esi, LazyEsiFile) and len(esi.device_heads) > 1:
        h = image.header
        matching = [d for d in esi.device_heads if (d.product_code, d.revision) == (h.product_code, h.revision)]
        if matching:
            return esi.device_at(matching[0].index)
    return select(esi, selector, policy)


@sii.command("check", short_help="Check IMAGE, or IMAGE against an ESI device.", epilog="""\b
Examples:
  ecattool sii check slave.bin                # CRC, size, category chain, strings, SMs, PDOs
  ecattool sii check slave.xml slave.bin      # also: does the image match the ESI device?
  ecattool sii check beckhoff_EL1xxx.xml el1008.bin --device EL1008 --policy newest --json
  ethercat sii_read -p 0 | ecattool sii check slave.xml -
\b
Exit codes: 0 no errors (no warnings either with --strict), 1 findings or invalid input.""")
@click.argument("files", nargs=-1, required=True, type=InputFile())
@click.option("--device", "selector", help="ESI device: type name, product[:revision] or list index "
              "(default: the device whose product code and revision match the image).")
@_POLICY
@click.option("--strict", is_flag=True, help="Warnings fail the check too.")
@json_option
def check_cmd(files: tuple[str, ...], selector: str | None, policy: str, strict: bool, as_json: bool) -> None:
    """Check IMAGE, or check IMAGE against an ESI device: `sii check [ESI] IMAGE`."""
    from ecattool.findings import has_errors
    from ecattool.sii.checks import check_against, check_file

    if len(files) > 2:
        raise click.UsageError("give IMAGE, or ESI IMAGE")
    image_path = files[-1]
    image, findings = check_file("<stdin>" if image_path == "-" else image_path, _stdin(image_path))
    if len(files) == 2 and image is not None:
        device = _select(files[0], selector, image, policy)
        findings += check_against(device, image)
    _findings_out(findings, as_json, {"image": image_path})
    raise SystemExit(1 if has_errors(findings, strict) else 0)


@sii.command("fix-crc", epilog="""\b
Example:
  ecattool sii fix-crc edited.bin -o fixed.bin""")
@click.argument("image", type=InputFile(allow_dash=True))
@output_option(required=True)
def fix_crc_cmd(image: str, output: str) -> None:
    """Recompute the checksum (word 7) over bytes 0-13 and write the repaired image."""
    from ecattool.sii.model import fix_crc

    img = _load(image)
    old = img.header.checksum & 0xFF
    fix_crc(img)
    _write_image(output, img, (image,))
    click.echo(f"checksum 0x{old:02X} -> 0x{img.header.checksum & 0xFF:02X}", err=True)


@sii.command("set-alias", epilog="""\b
Example:
  ecattool sii set-alias slave.bin 0x1001 -o slave-alias.bin""")
@click.argument("image", type=InputFile(allow_dash=True))
@click.argument("alias")
@output_option(required=True)
def set_alias_cmd(image: str, alias: str, output: str) -> None:
    """Set the configured station alias (word 4) to ALIAS and update the checksum."""
    from ecattool.sii.checks import set_alias

    img = _load(image)
    set_alias(img, parse_int_arg(alias, "station alias"))
    _write_image(output, img, (image,))


@sii.command("build", epilog="""\b
Examples:
  ecattool sii build slave.xml -o slave.bin
  ecattool sii build beckhoff_EL1xxx.xml --device EL1008 --policy newest -o el1008.bin
  ecattool sii build slave.xml --no-pdo-categories --size 256 -o slave.hex""")
@click.argument("esi", type=InputFile())
@click.option("--device", "selector", help="Device: type name, product[:revision] or list index (needed when "
              "the ESI describes several).")
@click.option("--no-pdo-categories", is_flag=True, help="Leave out TXPDO/RXPDO (PDOs come from CoE only).")
@click.option("--size", "size", help="EEPROM size in bytes (default: Eeprom/ByteSize, else 2048 or what fits).")
@_POLICY
@output_option(required=True)
def build_cmd(esi: str, selector: str | None, no_pdo_categories: bool, size: str | None, policy: str,
              output: str) -> None:
    """Build an SII EEPROM image from an ESI device; unused space is filled with 0xFF."""
    from ecattool.sii.builder import build
    from ecattool.sii.checks import built_image_problem

    byte_size = _size_arg(size)
    device = _select(esi, selector, policy=policy)
    img = build(device, pdo_categories=not no_pdo_categories, size=byte_size)
    _write_image(output, img, (esi,))
    # where the image does not pass `sii check` (the ESI's own categories), say so rather than stay silent
    problem = built_image_problem(device, img)
    if problem is not None:
        click.echo(f"ecattool: warning: {output}: {problem}", err=True)


def _size_arg(size: str | None) -> int | None:
    """--size as a number of bytes an EEPROM can have, checked before the ESI is read (the option's own error)."""
    byte_size = parse_int_arg(size, "EEPROM size") if size is not None else None
    if byte_size is not None:
        from ecattool.sii.builder import size_word_for

        try:
            size_word_for(byte_size)
        except InputError as exc:
            raise click.BadParameter(exc.message, param_hint="'--size'") from None
    return byte_size


@sii.command("diff", epilog="""\b
Examples:
  ecattool sii diff factory.bin rebuilt.bin
  ecattool sii diff a.bin b.hex --json
\b
Exit codes: 0 identical fields, 1 differences.""")
@click.argument("a", type=InputFile(allow_dash=True))
@click.argument("b", type=InputFile(allow_dash=True))
@json_option
def diff_cmd(a: str, b: str, as_json: bool) -> None:
    """Compare two images field by field and category by category (strings resolved)."""
    from ecattool.sii.compare import diff

    diffs = diff(_load(a), _load(b))
    if as_json:
        click.echo(dump_json({"a": a, "b": b, "identical": not diffs, "differences": [d.to_json() for d in diffs]}))
    else:
        for d in diffs:
            click.echo(str(d))
        click.echo(f"{len(diffs)} difference(s)" if diffs else "no differences")
    raise SystemExit(1 if diffs else 0)


# ------------------------------------------------------------------------------------------ on a live bus
@sii.command("read", epilog="""\b
Examples:
  ecattool sii read --target pysoem:eth0 --slave 1 -o axis2.sii.bin
  ecattool sii read --target sim:hdt -o hdt.bin
  ecattool sii read --target pysoem:eth0 --slave 2 --unchecked -o damaged.bin""")
@click.option("--target", required=True, metavar="TARGET",
              help="pysoem:IF, or the simulator sim:PROFILE,ESI… (KickCAT's binding has no SII access).")
@click.option("--slave", type=int, default=0, show_default=True, help="Position of the slave on the bus.")
@output_option(required=True, help="The image file (binary; written atomically, never over an input).")
@click.option("--unchecked", is_flag=True,
              help="Save the image even when it does not check out (a damaged EEPROM to repair); the problem is "
                   "still printed on stderr.")
@reset_bus_option
def read_cmd(target: str, slave: int, output: str, unchecked: bool) -> None:
    """Read a slave's SII EEPROM (the fixed area and the category chain to its end marker) into a file.

    The image is checked before it is written: not blank (0xFF) or all zero (what a read whose working counter
    failed gives), its checksum the CRC-8 of bytes 0-13, its category chain ending in the end marker. One that does
    not check out is exit 1 and no file (unless --unchecked)."""
    from ecattool.online.sii_access import read_problems

    check_output(output)  # an existing file without --force: refused before the bus is opened
    with open_live(target) as live:
        s = live.slave(slave)
        data = s.sii_read()
    problems = read_problems(data)
    if problems:
        more = f" (and {len(problems) - 1} more)" if len(problems) > 1 else ""
        text = f"slave {slave}: the SII read does not check out: {problems[0]}{more}"
        if not unchecked:
            raise TargetError(f"{text}; nothing written (--unchecked saves it anyway)")
        click.echo(f"ecattool: warning: {text}; saved as read (--unchecked)", err=True)
    write_output(output, data)


@sii.command("write", epilog="""\b
Examples:
  ecattool sii write fixed.bin --target pysoem:eth0 --slave 1 --backup old.bin
  ecattool sii write other-device.bin --target pysoem:eth0 --any-identity --backup old.bin
  ecattool sii write fixed.bin --target pysoem:eth0 --backup old.bin --force   # replace an old old.bin
\b
Checks before writing (as IgH's 'ethercat sii_write'): a whole number of words, the CRC of the configuration
area, the category chain up to its end marker, the size, and the identity against the slave's (unless
--any-identity). The categories are written first and the header with its CRC last (the CRC word is made
invalid before anything else): a write cut short leaves an image whose CRC fails, never a mixed one that
checks out. The image is read back and compared at the end.""")
@click.argument("image", type=InputFile())
@click.option("--target", required=True, metavar="TARGET",
              help="pysoem:IF, or the simulator sim:PROFILE,ESI… (KickCAT's binding has no SII access).")
@click.option("--slave", type=int, default=0, show_default=True, help="Position of the slave on the bus.")
@click.option("--backup", required=True, type=click.Path(dir_okay=False), metavar="FILE",
              help="Where the slave's current image is written before anything is written to it.")
@click.option("--any-identity", is_flag=True,
              help="Write even when the image's vendor, product code or revision is not the slave's (another "
                   "device's image; e.g. a firmware change).")
@click.option("--force", is_flag=True, callback=store_force,
              help="Replace an existing --backup file (it only ever means overwriting files).")
@reset_bus_option
def write_cmd(image: str, target: str, slave: int, backup: str, any_identity: bool, force: bool) -> None:
    """Write IMAGE to a slave's SII EEPROM, after the checks and a back-up of the old image. Exit status 1 when a
    check refuses the image: one line naming the first problem, and nothing is written (not even the back-up)."""
    from ecattool.fileio import read_bytes
    from ecattool.online.sii_access import sii_write

    data = read_bytes(image)
    check_output(backup, (image,))  # never over the image, an existing back-up only with --force
    with open_live(target) as live:
        problems = sii_write(live.slave(slave), data, image, backup, any_identity, overwrite_backup=force_requested())
    if problems:
        more = f" (and {len(problems) - 1} more)" if len(problems) > 1 else ""
        raise InputError(f"refused, nothing written: {problems[0]}{more}")
    click.echo(f"written; the old image is in {backup}")
