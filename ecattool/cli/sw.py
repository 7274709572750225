"""``ecattool sw``: Technosoft .sw EEPROM setup images."""

from __future__ import annotations

import sys
from pathlib import Path
from typing import TYPE_CHECKING

import click

from ecattool.cli.common import Decorated, console, json_option, output_option, print_json, table, write_output
from ecattool.cli.online import reset_bus_given, reset_bus_option
from ecattool.cli.paths import InputFile
from ecattool.errors import InputError, Location

if TYPE_CHECKING:
    from rich.table import Table

    from ecattool.esi.model import Device
    from ecattool.project.slave import Slave
    from ecattool.sw.apply import BlockCheck, DownloadReport
    from ecattool.sw.image import Block, SwImage
    from ecattool.sw.params import ParameterTable
    from ecattool.target.base import SlaveTarget


@click.group(epilog="""\b
Examples:
  ecattool sw info axis1.sw
  ecattool sw verify axis1.sw --target sim
  ecattool sw download axis1.sw --dry-run --mode 32
  ecattool sw foe axis1.sw -o FOESW_AXIS1.bin""")
def sw() -> None:
    """Technosoft .sw EEPROM setup images: inspect, check, convert, patch, build and download."""


def _image(path: str) -> SwImage:
    from ecattool.sw.build import load_image

    return load_image(Path(path))


def _params(path: str | None) -> ParameterTable | None:
    if path is None:
        return None
    from ecattool.sw.params import read_parameters

    return read_parameters(path)


_params_option = click.option("--parameters", "-p", "parameters", type=InputFile(),
                              help="EasyMotion parameters.cfg that names and types the setup variables.")


# ------------------------------------------------------------------------------------------------ info
@sw.command(epilog="""\b
Examples:
  ecattool sw info axis1.sw
  ecattool sw info FOESW_AXIS1.bin --json""")
@click.argument("file", type=InputFile())
@json_option
def info(file: str, as_json: bool) -> None:
    """Blocks of a .sw (or FoE .bin) image: range, word count, checksum, 2069h value and what each block is.

    Exit status 1 when an integrity word (setup-table checksum, identification sums, setup pointer) is wrong.
    """
    from ecattool.sw.layout import integrity_findings

    image = _image(file)
    findings = integrity_findings(image)
    if as_json:
        print_json({"blocks": [{"start": b.start, "end": b.end, "count": b.count, "checksum": b.checksum}
                               for b in image.blocks]})
    else:
        console().print(_blocks_table(file, image))
        for f in findings:
            click.echo(str(f))
    if findings:
        sys.exit(1)


def _blocks_table(file: str, image: SwImage) -> Table:
    """One row a block: range, words, checksum, the 2069h value that asks the drive for it, what the block is."""
    from rich.text import Text

    from ecattool.sw.layout import describe

    t = table(f"{file}: {len(image)} blocks, {image.total_words} words",
              ["start", "end", "words", "checksum", "2069h", "block"])
    for i in describe(image):
        b = i.block
        t.add_row(f"0x{b.start:04X}", f"0x{b.end:04X}", str(b.count), f"0x{b.checksum:04X}",
                  f"0x{b.checksum_request:08X}", Text(i.description))
    return t


# ------------------------------------------------------------------------------------------------- FoE
@sw.command(epilog="""\b
Examples:
  ecattool sw foe axis1.sw -o FOESW_AXIS1.bin
  ecattool sw foe axis1.sw -o FOESW_AXIS1.efw""")
@click.argument("file", type=InputFile())
@output_option(required=True, help="FoE file: FOESW_ prefix, at most 14 characters without .bin/.efw.")
def foe(file: str, output: str) -> None:
    """Convert a .sw image to a FoE setup file (the drive's rules for the file name are enforced)."""
    from ecattool.sw.foe import check_foe_name, to_foe

    if output == "-":
        raise InputError("a FoE setup file needs a file name the drive accepts; give -o FOESW_NAME.bin")
    check_foe_name(output)
    write_output(output, to_foe(_image(file)), (file,))


@sw.command("from-foe", epilog="""\b
Examples:
  ecattool sw from-foe FOESW_AXIS1.bin -o axis1.sw
  ecattool sw from-foe FOESW_AXIS1.bin | head""")
@click.argument("file", type=InputFile())
@output_option()
def from_foe_cmd(file: str, output: str | None) -> None:
    """Convert a FoE setup file back to .sw text (CRLF, as the vendor tools write it)."""
    from ecattool.sw.foe import read_foe
    from ecattool.sw.image import write

    write_output(output, write(read_foe(file)), (file,))


# ---------------------------------------------------------------------------------------------- targets
def _open_target(spec: str, slave: int, device: Device | None = None) -> SlaveTarget:
    """The slave at ``slave`` of the target ``spec`` (ecattool.online.targets.open_slave): with ``sim``, a simulated
    bus of ``device`` at that position (a Technosoft iPOS without one)."""
    from ecattool.online.targets import open_slave

    if device is None:  # .sw images are Technosoft's: a bare 'sim' is an iPOS, a real bus gets its timeouts
        from ecattool import profiles

        device = profiles.load("technosoft-ipos")
    return open_slave(spec, [device], slave, reset_bus_given())


def _project_drive(project: str, name: str | None, allow_errors: bool = False) -> tuple[Slave, str]:
    """The slave ``name`` of a project's machine (or its only slave, or the one with an ``sw:``) and the
    project's default target; a project with lint errors for it is refused unless ``allow_errors``."""
    from ecattool.project.machine import load_machine

    machine = load_machine(project)
    return machine.sw_drive(name, allow_errors=allow_errors), machine.target


_target_option = click.option("--target", default=None,
                              help="'sim' (a simulated Technosoft iPOS; the default) or 'pysoem:<interface>'; "
                                   "with --project, the project's target.")
_slave_option = click.option("--slave", default=None, type=int, help="Slave position on the bus (default 0, or the project's).")
_project_option = click.option("--project", type=InputFile(),
                               help="Project file: the drive's device, bus position, target and .sw file.")
_drive_option = click.option("--drive", "drive_name", help="Drive name in --project (needed when it has several).")
_allow_errors_option = click.option("--allow-errors", is_flag=True,
                                    help="With --project: use the drive even when lint reports errors for it.")
_preload_option = click.option("--preload", type=InputFile(),
                               help="Simulator only: program this .sw into the simulated EEPROM first.")


def _target_options(f: Decorated) -> Decorated:
    """--target, --reset-bus, --slave, --project, --drive, --preload and --allow-errors (verify, download, upload)."""
    for option in (_allow_errors_option, _preload_option, _drive_option, _project_option, _slave_option,
                   reset_bus_option, _target_option):
        f = option(f)
    return f


def _project_slave(project: str, drive_name: str | None, allow_errors: bool, target: str | None,
                   slave: int | None) -> tuple[Slave, str | None, int | None]:
    """(the project's slave, the target: the option's else the project's, the position: the option's else the
    slave's) for the commands that take --project."""
    rd, project_target = _project_drive(project, drive_name, allow_errors)
    return rd, target or project_target, rd.position if slave is None else slave


def _target_and_image(file: str | None, target: str | None, slave: int | None, project: str | None,
                      drive_name: str | None, preload: str | None,
                      allow_errors: bool = False) -> tuple[SlaveTarget, SwImage, str, str]:
    """(target, image, image name, target name) for verify/download."""
    device = None
    image = None
    name = file
    if project is not None:
        rd, target, slave = _project_slave(project, drive_name, allow_errors, target, slave)
        device = rd.device
        if file is None:
            cfg = rd.drive.sw_config
            if cfg is None or rd.sw_image is None:
                raise InputError(f"drive {rd.drive.name!r} has no readable sw image; give FILE", Location(project))
            image, name = rd.sw_image, cfg.file
    elif drive_name is not None:
        raise InputError("--drive needs --project")
    if image is None:
        if file is None:
            raise click.UsageError("give the .sw FILE (or --project with a drive that has 'sw:')")
        image = _image(file)
    spec = target or "sim"
    return _open_preloaded(spec, slave, device, preload), image, name or "", spec


def _open_preloaded(spec: str, slave: int | None, device: Device | None, preload: str | None) -> SlaveTarget:
    """The slave of ``spec``; on the simulator with ``preload`` programmed into its EEPROM first."""
    if preload:
        from ecattool.target.opener import parse_target

        if parse_target(spec).kind != "sim":  # before a real master is opened for nothing
            raise InputError("--preload is for the simulator only")
    tgt = _open_target(spec, slave or 0, device)
    if preload:
        from ecattool.sw.apply import download

        if not download(_image(preload), tgt, reset=True).ok:
            raise InputError(f"could not preload {preload} into the simulator", Location(preload))
    return tgt


def _checks_table(title: str, checks: list[BlockCheck]) -> Table:
    from rich.text import Text

    t = table(title, ["start", "end", "words", "file", "drive", "result"])
    for c in checks:
        b = c.block
        t.add_row(f"0x{b.start:04X}", f"0x{b.end:04X}", str(b.count), f"0x{c.expected:04X}",
                  "-" if c.actual is None else f"0x{c.actual:04X}",
                  Text("ok" if c.ok else (c.error or "DIFFERENT")))
    return t


@sw.command(epilog="""\b
Examples:
  ecattool sw verify axis1.sw --target sim
  ecattool sw verify axis1.sw --target pysoem:eth0 --slave 2 --json
  ecattool sw verify --project machine.yaml --drive x_axis""")
@click.argument("file", type=InputFile(), required=False)
@_target_options
@json_option
def verify(file: str | None, target: str | None, slave: int | None, project: str | None, drive_name: str | None,
           preload: str | None, allow_errors: bool, as_json: bool) -> None:
    """Compare the drive's EEPROM checksums (2069h/206Ah) with the file, block by block.

    Exit status 1 when any block differs: reload it with 'ecattool sw download'.
    """
    from ecattool.sw.apply import verify as verify_image

    tgt, image, name, spec = _target_and_image(file, target, slave, project, drive_name, preload, allow_errors)
    checks = verify_image(image, tgt)
    if as_json:
        print_json({"ok": all(c.ok for c in checks), "blocks": [c.to_json() for c in checks]})
    else:
        console().print(_checks_table(f"{name} on {spec}", checks))
    if not all(c.ok for c in checks):
        sys.exit(1)


@sw.command(epilog="""\b
Examples:
  ecattool sw download axis1.sw --dry-run
  ecattool sw download axis1.sw --dry-run --mode 32 --json
  ecattool sw download axis1.sw --target sim
  ecattool sw download axis1.sw --target pysoem:eth0 --slave 1
  ecattool sw download --project machine.yaml --drive x_axis""")
@click.argument("file", type=InputFile(), required=False)
@click.option("--dry-run", is_flag=True, help="Only list the SDO writes (a startup list); touch no drive.")
@click.option("--mode", type=click.Choice(["16", "32"]), default="16", show_default=True,
              help="2065h data width: one word per write, or two (low word at the lower address).")
@click.option("--force", is_flag=True, help="Write every block, not only those whose checksum differs.")
@click.option("--no-reset", is_flag=True, help="Do not reset the drive (2080h) after a successful download.")
@_target_options
@json_option
def download(file: str | None, dry_run: bool, mode: str, force: bool, no_reset: bool, target: str | None,
             slave: int | None, project: str | None, drive_name: str | None, preload: str | None,
             allow_errors: bool, as_json: bool) -> None:
    """Program the image into the drive EEPROM over CoE (2064h/2065h), verify, then reset.

    Without --dry-run only the blocks whose drive checksum differs are written; each is verified after
    writing; the drive is reset (2080h, no SDO reply) only when every block checks out. A failed block is
    reported and the command exits 1; running it again repairs the drive.
    """
    if dry_run:
        if file is None:
            raise click.UsageError("--dry-run needs the .sw FILE")
        _render_plan(file, int(mode), not no_reset, as_json)
        return
    tgt, image, file, _ = _target_and_image(file, target, slave, project, drive_name, preload, allow_errors)
    report = _run_download(image, tgt, int(mode), not no_reset, force, show_progress=not as_json)
    if as_json:
        print_json(report.to_json())
    else:
        _render_download(file, report, no_reset)
    if not report.ok:
        sys.exit(1)


def _render_plan(file: str, mode: int, reset: bool, as_json: bool) -> None:
    """``download --dry-run``: the SDO writes of the download plan, as JSON or a table."""
    from ecattool.sw.plan import download_plan

    plan = download_plan(_image(file), mode, reset=reset, name=file)
    if as_json:
        print_json({"mode": mode, "commands": [
            {"index": c.index, "subindex": c.subindex, "value": c.int_value, "size": len(c.data),
             "expect_reply": c.expect_reply, "comment": c.comment} for c in plan]})
        return
    t = table(f"{file}: {len(plan)} SDO writes ({mode}-bit)", ["#", "object", "value", "comment"])
    for n, c in enumerate(plan, 1):
        t.add_row(str(n), c.address, f"0x{c.int_value:0{2 * len(c.data)}X}", c.comment)
    console().print(t)


def _render_download(file: str, report: DownloadReport, no_reset: bool) -> None:
    """What a download did: nothing to write, or the blocks after writing, the write errors and the reset."""
    out = console()
    if not report.written:
        out.print(f"{file}: every block already matches the drive; nothing written", markup=False)
        return
    out.print(_checks_table(f"{file}: after writing {len(report.written)} block(s)", report.after))
    for start, err in report.write_errors.items():
        out.print(f"block 0x{start:04X}: write failed: {err}", markup=False)
    out.print(_reset_line(report, no_reset))


def _reset_line(report: DownloadReport, no_reset: bool) -> str:
    """The last line of a download that wrote something: whether the drive was reset, and why not."""
    if report.reset:
        return "drive reset to load the new setup"
    if report.ok and no_reset:
        return "every block checks out; drive NOT reset (--no-reset): reset it to load the new setup"
    return "drive NOT reset: some blocks are still different; run the download again"


def _run_download(image: SwImage, target: SlaveTarget, mode: int, reset: bool, force: bool,
                  show_progress: bool) -> DownloadReport:
    from ecattool.sw.apply import download as download_image

    if not (show_progress and sys.stderr.isatty()):
        return download_image(image, target, None, mode, reset, force)
    from rich.progress import BarColumn, Progress, TaskProgressColumn, TextColumn

    with Progress(TextColumn("{task.description}"), BarColumn(), TaskProgressColumn(),
                  console=console(stderr=True), transient=True) as bar:
        task = bar.add_task("EEPROM", total=None)

        def progress(done: int, total: int, block: Block) -> None:
            bar.update(task, completed=done, total=total, description=f"block 0x{block.start:04X}")

        return download_image(image, target, progress, mode, reset, force)


# ----------------------------------------------------------------------------------- setup table views
@sw.command(epilog="""\b
Examples:
  ecattool sw show axis1.sw
  ecattool sw show axis1.sw --parameters parameters.cfg --json""")
@click.argument("file", type=InputFile())
@_params_option
@json_option
def show(file: str, parameters: str | None, as_json: bool) -> None:
    """List the setup table as variables and values (named and typed with --parameters)."""
    from ecattool.sw.setup import format_value, setup_values

    table_, values = setup_values(_image(file), _params(parameters))
    if as_json:
        print_json({"start": table_.block.start, "config_id": table_.config_id, "sections": list(table_.sizes),
                    "checksum": table_.stored_checksum, "values": [v.to_json() for v in values],
                    "section3_decoded": parameters is not None})
        return
    t = table(f"{file}: setup table at 0x{table_.block.start:04X}, configuration id 0x{table_.config_id:04X}",
              ["sect", "address", "name", "type", "raw", "value", "unit"])
    for v in values:
        width = 4 * len(v.entry.words)
        t.add_row(str(v.entry.section), f"0x{v.entry.address:04X}", v.name or "", v.type,
                  f"0x{v.entry.raw:0{width}X}", format_value(v.type, v.value), v.unit)
    c = console()
    c.print(t)
    if parameters is None and table_.section3:
        c.print(f"section 3 ({len(table_.section3)} words) needs --parameters parameters.cfg to be decoded", markup=False)


@sw.command(epilog="""\b
Examples:
  ecattool sw patch axis1.sw -p parameters.cfg --set PWMPER=2250 --set CACC=3.18311 -o axis1_new.sw
  ecattool sw patch axis1.sw --set 0x0250=2 -o axis1_new.sw""")
@click.argument("file", type=InputFile())
@click.option("--set", "sets", multiple=True, required=True, metavar="NAME=VALUE",
              help="Variable (name from --parameters, or address 0xADDR) and new value; repeatable.")
@_params_option
@output_option(required=True)
def patch(file: str, sets: tuple[str, ...], parameters: str | None, output: str) -> None:
    """Change setup-table values; every checksum, sum and pointer word is recomputed."""
    from ecattool.sw.image import write
    from ecattool.sw.setup import patch as patch_image

    assignments = []
    for s in sets:
        if "=" not in s:
            raise click.BadParameter(f"{s!r}: write NAME=VALUE", param_hint="--set")
        k, v = s.split("=", 1)
        assignments.append((k, v))
    image = _image(file)
    new = patch_image(image, assignments, _params(parameters))
    write_output(output, write(new), (file, parameters) if parameters else (file,))


@sw.command(epilog="""\b
Examples:
  ecattool sw diff old.sw new.sw
  ecattool sw diff old.sw new.sw --parameters parameters.cfg --json""")
@click.argument("a", type=InputFile())
@click.argument("b", type=InputFile())
@_params_option
@json_option
def diff(a: str, b: str, parameters: str | None, as_json: bool) -> None:
    """Compare two images by address and, in the setup table, by variable. Exit 1 when they differ."""
    from ecattool.sw.setup import diff as diff_images

    diffs = diff_images(_image(a), _image(b), _params(parameters))
    if as_json:
        print_json({"same": not diffs, "differences": [d.to_json() for d in diffs]})
    else:
        t = table(f"{a} vs {b}: {len(diffs)} difference(s)", ["address", "name", "a", "b"])

        def fmt(v: int | None, shown: str | None) -> str:
            if v is None:
                return "-"
            return f"{shown} (0x{v:X})" if shown is not None else f"0x{v:X} ({v})"

        for d in diffs:
            name = f"{d.name} ({d.type})" if d.type else d.name or ""
            t.add_row(f"0x{d.address:04X}", name, fmt(d.a, d.a_value), fmt(d.b, d.b_value))
        console().print(t)
    if diffs:
        sys.exit(1)


@sw.command(epilog="""\b
Examples:
  ecattool sw build samples/sw/build.yaml -o axis1.sw""")
@click.argument("spec", type=InputFile())
@output_option(required=True)
def build(spec: str, output: str) -> None:
    """Assemble an image from a YAML spec (base image, extra blocks, setup values) with correct integrity words."""
    from ecattool.sw.build import build as build_image
    from ecattool.sw.image import write

    named: list[Path] = []  # the files the spec names (base, blocks, parameters): -o must not be one of them
    image = build_image(spec, named)
    write_output(output, write(image), (spec, *map(str, named)))


@sw.command(epilog="""\b
Examples:
  ecattool sw upload --project machine.yaml --target pysoem:eth0 -o axis1-backup.sw
  ecattool sw upload --like axis1.sw --target pysoem:eth0 --slave 1 -o axis2.sw
  ecattool sw upload --range 0x5638-0x5A37 --target sim --preload axis1.sw -o back.sw --json""")
@click.option("--like", "like", type=InputFile(), help="Read the block ranges of this .sw.")
@click.option("--range", "ranges", multiple=True, metavar="START-END",
              help="An EEPROM word range to read (inclusive), e.g. 0x5638-0x5A37; repeatable.")
@_target_options
@output_option(help="The .sw file to write (CRLF, as the vendor tools write it); default: stdout, or with --json "
                   "inside the JSON document.")
@json_option
def upload(like: str | None, ranges: tuple[str, ...], target: str | None, slave: int | None, project: str | None,
           drive_name: str | None, preload: str | None, allow_errors: bool, output: str | None, as_json: bool) -> None:
    """Read a Technosoft drive's EEPROM setup into a .sw: the block ranges of the project's .sw (--project), of
    another .sw (--like) or given (--range). Every block is checked by the drive's own checksum (2069h/206Ah);
    the file is written only when all of them match (exit status 1 otherwise)."""
    from ecattool.sw.image import write
    from ecattool.sw.upload import upload as do_upload, upload_ranges

    ref = _image(like) if like else None
    device = None
    if project is not None:
        rd, target, slave = _project_slave(project, drive_name, allow_errors, target, slave)
        device = rd.device
        ref = ref or rd.sw_image
    spec = target or "sim"
    image, checks = do_upload(_open_preloaded(spec, slave, device, preload), upload_ranges(ranges, ref))
    ok = all(c.ok for c in checks)
    _write_upload(write(image), checks, ok, output, tuple(x for x in (like, project, preload) if x), as_json, spec)
    if not ok:
        sys.exit(1)


def _write_upload(text: bytes, checks: list[BlockCheck], ok: bool, output: str | None, inputs: tuple[str, ...],
                  as_json: bool, spec: str) -> None:
    """The .sw read, written only when every block checks out, and the checks as JSON or a table."""
    to_file = output not in (None, "-")
    if ok and (to_file or not as_json):
        write_output(output, text, inputs)
    if as_json:
        print_json({"ok": ok, "output": output if ok and to_file else None, "blocks": [c.to_json() for c in checks],
                    **({} if to_file or not ok else {"sw": text.decode("ascii", "replace")})})
    elif to_file:
        console().print(_checks_table(f"read from {spec}" + ("" if ok else ": NOT written"), checks))
