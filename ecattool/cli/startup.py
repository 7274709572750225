"""``ecattool startup``: export, import and convert startup lists between master formats."""

from __future__ import annotations

from typing import TYPE_CHECKING

import click

from ecattool.cli.common import (
    Decorated,
    console,
    json_option,
    output_option,
    print_json,
    table,
    write_output,
)
from ecattool.cli.paths import InputFile
from ecattool.errors import InputError, Location

if TYPE_CHECKING:
    from collections.abc import Sequence

    from rich.console import Console
    from rich.table import Table

    from ecattool.startup.config import SlaveConfig
    from ecattool.startup.model import StartupList

_FORMAT_NAMES = ("eni", "twincat", "igh", "pysoem", "ros2", "ecmc", "json", "csv", "lcec")
#: the formats ecattool can read (igh and pysoem are written only; lcec is read only), as the format registry
#: says (tests/test_cli_contract.py checks), without importing it when the CLI starts
_READ_FORMATS = ("eni", "twincat", "ros2", "ecmc", "json", "csv", "lcec")




@click.group("startup", epilog="""\b
Examples:
  ecattool startup import ros2_technosoft_ipos3604.yaml
  ecattool startup export --from drive.json --format igh -o drive_config.c
  ecattool startup convert ecmciPOSXXXX.cmd --format eni -o ipos.eni.xml""")
def startup() -> None:
    """Export and import startup lists (SDO init commands) for EtherCAT masters.

    Formats: ENI InitCmds, TwinCAT startup lines, IgH C, pysoem, ethercat_driver_ros2 YAML, ecmc scripts,
    JSON and CSV; LinuxCNC lcec configurations can be read.
    """


def _read_with_format(path: str, fmt: str | None) -> tuple[list[SlaveConfig], str]:
    """Read a startup configuration from a file, or from stdin for ``-``; also say which format it was."""
    from ecattool.fileio import read_input
    from ecattool.startup import detect_format, import_bytes

    source = "<stdin>" if path == "-" else path
    data = read_input(path)
    name = fmt or detect_format(data, source)
    return import_bytes(data, source, name), name


def _read(path: str, fmt: str | None) -> list[SlaveConfig]:
    return _read_with_format(path, fmt)[0]


def _report_import(configs: list[SlaveConfig], source: str) -> None:
    """Every note the import made goes to stderr (what was skipped or reinterpreted); a source that gives
    nothing to convert is an error, not an empty file and exit 0."""
    from ecattool.findings import Severity

    notes = [n for c in configs for n in c.notes]
    for n in notes:
        click.echo(str(n), err=True)
    if not any(c.commands or c.has_pdo_info or c.dc_assign_activate or c.soe_commands for c in configs):
        raise InputError("nothing to convert: no startup command, PDO or DC setting was read"
                         + (f" ({len(notes)} note(s) above say what was skipped)" if notes else ""),
                         Location(source))  # --drive chose slaves with nothing (an import of nothing fails earlier)
    skipped = [n for n in notes if n.severity is not Severity.INFO]
    if skipped:
        click.echo(f"{source}: {len(skipped)} part(s) of the source were not converted (warnings above)", err=True)


def _with_cycle(configs: list[SlaveConfig], sync0_cycle: int | None) -> list[SlaveConfig]:
    """``--sync0-cycle``: the SYNC0 cycle of slaves that activate DC without giving one (a ros2 file)."""
    if sync0_cycle is not None:
        for c in configs:
            if c.dc_assign_activate and not c.dc_cycle_ns:
                c.dc_cycle_ns = sync0_cycle
    return configs


def write_startup(configs: Sequence[SlaveConfig | StartupList], fmt: str, output: str | None, inputs: tuple[str, ...], lossy: bool = False) -> None:
    """Write ``configs`` in ``fmt``; what the format cannot carry refuses the export, or with ``--lossy`` is
    printed to stderr, one line each, with the count."""
    from ecattool.startup import export, losses

    text = export(configs, fmt, lossy=lossy)
    lost = losses(configs, fmt)
    for what in lost:
        click.echo(f"not written ({fmt}): {what}", err=True)
    write_output(output, text, inputs)
    if lost:
        click.echo(f"{len(lost)} part(s) of the configuration are not in the {fmt} output (--lossy)", err=True)


def lossy_option(f: Decorated) -> Decorated:
    return click.option("--lossy", is_flag=True,
                        help="Write the output even where the format cannot carry part of the configuration "
                             "(one-shot writes, DC, SoE, PDO tables, identity); each loss is printed. Without "
                             "it such an export fails and lists them.")(f)


def _sync0_option(f: Decorated) -> Decorated:
    return click.option("--sync0-cycle", type=click.IntRange(min=1, max=0xFFFFFFFF), metavar="NS",
                        help="SYNC0 cycle in ns for slaves that activate DC without giving a cycle (ros2 files); "
                             "an ENI needs it.")(f)


@startup.command("export", epilog="""\b
Examples:
  ecattool startup export --from drive.json --format twincat
  ecattool startup export --from ecmciPOSXXXX.cmd --format igh -o ipos.c
  ecattool startup export --from test_eni.xml --format pysoem -o startup_pysoem.py
  ecattool startup export --project samples/technosoft_ipos/project.yaml --format eni -o x.xml
  ecattool startup export --project machine.yaml --drive y_axis --format ros2 -o y_axis.yaml""")
@click.option("--from", "source", type=InputFile(allow_dash=True),
              help="Startup configuration to read (ecattool JSON or any importable format, detected from "
                   "content; '-' = stdin).")
@click.option("--project", "project", type=InputFile(),
              help="An ecattool project file instead of --from: every drive's startup list, PDOs and DC "
                   "(refused when the project has lint errors).")
@click.option("--from-format", type=click.Choice(_READ_FORMATS), help="Format of --from (default: detect).")
@click.option("--format", "fmt", required=True, type=click.Choice(_FORMAT_NAMES[:-1]), help="Format to write.")
@click.option("--drive", "drives", multiple=True,
              help="Only this drive of the project (or slave of --from): name or bus position; repeatable. "
                   "TwinCAT and ros2 files hold one slave.")
@_sync0_option
@click.option("--allow-errors", is_flag=True, help="With --project: export even when lint reports errors.")
@lossy_option
@output_option()
def export_cmd(source: str | None, project: str | None, from_format: str | None, fmt: str, drives: tuple[str, ...],
               sync0_cycle: int | None, allow_errors: bool, lossy: bool, output: str | None) -> None:
    """Write the startup list of FILE (--from) or of a project (--project) in a master's format (stdout
    unless -o)."""
    from ecattool.startup import select_slaves

    if (source is None) == (project is None):
        raise click.UsageError("give exactly one of --from FILE or --project PROJECT")
    if project is not None:
        if from_format is not None:
            raise click.UsageError("--from-format belongs to --from, not --project")
        from ecattool.project.loader import project_inputs

        configs = _project_configs(project, drives, allow_errors)
        write_startup(_with_cycle(configs, sync0_cycle), fmt, output, tuple(project_inputs([project])), lossy)
        return
    assert source is not None
    configs = select_slaves(_read(source, from_format), drives)
    _report_import(configs, source)
    write_startup(_with_cycle(configs, sync0_cycle), fmt, output, (source,), lossy)


def _project_configs(project: str, drives: tuple[str, ...], allow_errors: bool) -> list[SlaveConfig]:
    """The slave configurations of the project's drives (those ``drives`` name, else all), its export warnings
    for them on stderr."""
    from ecattool.project.export import export_warnings, slave_configs
    from ecattool.project.machine import load_machine
    from ecattool.startup import select_slaves

    machine = load_machine(project)
    configs = select_slaves(slave_configs(machine, allow_errors), drives)
    for f in export_warnings(machine, {c.name for c in configs}):
        click.echo(str(f), err=True)
    return configs


@startup.command("convert", epilog="""\b
Examples:
  ecattool startup convert ros2_elmo_gold.yaml --format eni --sync0-cycle 1000000 -o elmo.eni.xml
  ecattool startup convert AX5206-AM8032-async.xml --format json -o ax5206.json
  ecattool startup convert ros2_elmo_gold.yaml --format twincat --lossy -o elmo.txt""")
@click.argument("input_file", type=InputFile())
@click.option("--format", "fmt", required=True, type=click.Choice(_FORMAT_NAMES[:-1]), help="Format to write.")
@click.option("--from-format", type=click.Choice(_READ_FORMATS), help="Format of INPUT_FILE (default: detect).")
@click.option("--drive", "drives", multiple=True,
              help="Only this slave of INPUT_FILE: name or bus position; repeatable. TwinCAT and ros2 files hold "
                   "one slave.")
@_sync0_option
@lossy_option
@output_option()
def convert_cmd(input_file: str, fmt: str, from_format: str | None, drives: tuple[str, ...], sync0_cycle: int | None,
                lossy: bool, output: str | None) -> None:
    """Convert INPUT_FILE into another startup format (stdout unless -o, as `startup export`).

    Every note of the import (what the source holds that was not converted) is printed to stderr; a
    source with nothing to convert is an error (exit 1).
    """
    from ecattool.startup import select_slaves

    configs = select_slaves(_read(input_file, from_format), drives)
    _report_import(configs, input_file)
    write_startup(_with_cycle(configs, sync0_cycle), fmt, output, (input_file,), lossy)


@startup.command("import", epilog="""\b
Examples:
  ecattool startup import ros2_technosoft_ipos3604.yaml
  ecattool startup import test_eni.xml --json
  cat startup.txt | ecattool startup import - --from-format twincat""")
@click.argument("input_file", type=InputFile(allow_dash=True))
@click.option("--from-format", type=click.Choice(_READ_FORMATS), help="Format of INPUT_FILE (default: detect).")
@json_option
def import_cmd(input_file: str, from_format: str | None, as_json: bool) -> None:
    """Read a startup configuration and show what was read: slaves, commands, PDOs, notes."""
    from ecattool.startup.formats.jsonfmt import slave_to_json

    configs, fmt = _read_with_format(input_file, from_format)
    if as_json:
        print_json({"file": input_file, "format": fmt, "slaves": [
            {**slave_to_json(c), "commands": [{**d, "source": str(cmd.source) if cmd.source else None}
                                              for d, cmd in zip(slave_to_json(c)["commands"], c.commands)]}
            for c in configs]})
        return
    out = console()
    for c in configs:
        _render_slave(out, c)


def _render_slave(out: Console, c: SlaveConfig) -> None:
    """What was read of one slave: identity and position, DC, its startup commands, PDOs, SoE count and notes."""
    ident = f"  {c.identity}" if c.identity else ""
    pos = f" at position {c.position}" if c.position is not None else ""
    out.print(f"[bold]{c.label}[/bold]{pos}{ident}")
    if c.dc_assign_activate:
        out.print(f"  DC assign activate 0x{c.dc_assign_activate:04X}"
                  + (f", cycle {c.dc_cycle_ns} ns" if c.dc_cycle_ns else ""))
    if c.commands:
        out.print(_commands_table(c))
    for direction, pdos in (("RxPDO", c.rx_pdos), ("TxPDO", c.tx_pdos)):
        for p in pdos:
            entries = ", ".join(f"{e.index:04X}:{e.subindex:02X}/{e.bit_len}" for e in p.entries)
            out.print(f"  {direction} 0x{p.index:04X} ({p.bit_size} bits): {entries}")
    if c.soe_commands:
        out.print(f"  {len(c.soe_commands)} SoE init command(s) (kept; shown with --json)")
    for n in c.notes:
        out.print(f"  {n}", markup=False)


def _commands_table(c: SlaveConfig) -> Table:
    from ecattool.od.display import value_text

    t = table(f"{len(c.commands)} startup command(s)", ["line", "tr", "object", "value", "CA", "comment"])
    for cmd in c.commands:
        # decoded by size (2000 (0x000007D0), not d0070000); complete-access data stays bytes
        value = cmd.data.hex(" ") if cmd.complete_access else value_text(cmd.data, index=cmd.index)
        t.add_row(str(cmd.source.line if cmd.source and cmd.source.line else ""), cmd.transition,
                  cmd.address, value, "CA" if cmd.complete_access else "", cmd.comment)
    return t
